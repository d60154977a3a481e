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
  message(STATUS "hil: sanitizers ${HIL_SANITIZE} (runtime ${HIL_SANITIZER_RUNTIME})")
endif()
