# Sanitizer builds (docs/sanitizers.md): HIL_SANITIZE=address,undefined (ASan + UBSan) or thread
# (TSan). Every target of the tree is instrumented, generated IDL code included; the libraries
# from Debian (Fast DDS, libmodbus, yaml-cpp, ...) are not, so TSan sees their synchronisation
# through the pthread calls it intercepts (tests/sanitizers/tsan.supp names what it cannot see).
# Any report fails the test: UBSan does not recover, ASan/TSan stop at the first error
# (CMakePresets.json sets the run-time options).
set(HIL_SANITIZE "" CACHE STRING "Sanitizers to build with: address,undefined | thread | empty (none)")
set_property(CACHE HIL_SANITIZE PROPERTY STRINGS "" "address,undefined" "address" "undefined" "thread")

if(HIL_SANITIZE)
  if(NOT HIL_SANITIZE MATCHES "^(address|undefined|thread)(,(address|undefined|thread))*$")
    message(FATAL_ERROR "HIL_SANITIZE='${HIL_SANITIZE}': expected a comma-separated list of address, undefined, thread")
  endif()
  if(HIL_SANITIZE MATCHES "thread" AND HIL_SANITIZE MATCHES "address")
    message(FATAL_ERROR "HIL_SANITIZE='${HIL_SANITIZE}': thread and address cannot be combined (two builds)")
  endif()
  set(HIL_SANITIZE_FLAGS -fsanitize=${HIL_SANITIZE} -fno-omit-frame-pointer)
  if(HIL_SANITIZE MATCHES "undefined")
    # A UB report aborts the program (and fails its test) instead of printing and going on.
    list(APPEND HIL_SANITIZE_FLAGS -fno-sanitize-recover=all)
  endif()
  add_compile_options(${HIL_SANITIZE_FLAGS})
  # GCC's flow warnings see the instrumentation's extra paths: under -fsanitize it reports
  # "may be used uninitialized" inside libstdc++'s <regex> and <functional>, which the normal
  # build (same code, same -Werror) does not. The normal build keeps the warning.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    add_compile_options(-Wno-maybe-uninitialized)
  endif()
  add_link_options(-fsanitize=${HIL_SANITIZE})
  # The sanitizer runtime, for what must preload it: a Python extension built with ASan/TSan is
  # loaded into an interpreter that is not (tests/python).
  if(HIL_SANITIZE MATCHES "address")
    set(_hil_san_lib libasan.so)
  elseif(HIL_SANITIZE MATCHES "thread")
    set(_hil_san_lib libtsan.so)
  else()
    set(_hil_san_lib libubsan.so)
  endif()
  execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=${_hil_san_lib}
                  OUTPUT_VARIABLE HIL_SANITIZER_RUNTIME OUTPUT_STRIP_TRAILING_WHITESPACE)
  get_filename_component(HIL_SANITIZER_RUNTIME "${HIL_SANITIZER_RUNTIME}" REALPATH)
  # With it libstdc++: the runtime's __cxa_throw interceptor must find the real one at start-up,
  # and the interpreter loads libstdc++ only later, with the module (else the first C++ exception
  # is "CHECK failed: real___cxa_throw").
  execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libstdc++.so.6
                  OUTPUT_VARIABLE _hil_libstdcxx OUTPUT_STRIP_TRAILING_WHITESPACE)
  get_filename_component(_hil_libstdcxx "${_hil_libstdcxx}" REALPATH)
  set(HIL_SANITIZER_PRELOAD "${HIL_SANITIZER_RUNTIME}:${_hil_libstdcxx}")
  message(STATUS "hil: sanitizers ${HIL_SANITIZE} (runtime ${HIL_SANITIZER_RUNTIME})")
endif()

# Sanitized tests run 2-3x slower: tests whose own limits are tight for that scale them by
# HIL_TEST_TIME_SCALE (the sanitizer test presets export it to the test processes too).
if(HIL_SANITIZE)
  set(HIL_TEST_TIME_SCALE 3)
else()
  set(HIL_TEST_TIME_SCALE 1)
endif()
