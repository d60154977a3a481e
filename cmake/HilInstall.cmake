# `cmake --install`: the library modules as the CMake package `hil` (find_package(hil), targets
# hil::<module>) and as the pkg-config module `hil`, their headers (the generated IDL headers in
# include/hil/idl), the examples and a licence (docs/install.md). Included last by the top-level
# CMakeLists.txt, once every module target exists.
#
# The libraries stay static, as the build makes them: no SONAME/RPATH policy to keep, and the
# installed `hil` is the very binary the tests ran. The cost is that a consumer links their
# private dependencies too (spdlog, yaml-cpp, libmodbus): hilConfig.cmake finds them and hil.pc
# lists them.
include(CMakePackageConfigHelpers)

# Target -> exported name (hil::<name>). Exported ones must only link exported or imported targets.
set(_hil_exports
  hil_so3 so3
  hil_error error
  hil_solver solver
  hil_parallel parallel
  hil_calibration calibration
  hil_contact_id contact_id
  hil_format format
  hil_idl_types idl_types
  hil_idl idl
  hil_messages messages
  hil_drivers drivers
  hil_acquisition acquisition
  hil_report report
  hil_import import
  hil_diagnose diagnose
  hil_rig_service rig_service
  hil_models models
  hil_keystore keystore
  hil_service_contact service_contact
  hil_service_diagnose service_diagnose
  hil_service_stiffness service_stiffness
  hil_service_workers service_workers)
set(HIL_CONFIG_MCAP_DEPS "")
set(HIL_PC_REQUIRES "eigen3 yaml-cpp spdlog libmodbus urdfdom orocos-kdl")
if(TARGET hil_mcap)
  list(APPEND _hil_exports hil_mcap mcap)
  # hil::mcap's private links (zstd and lz4 chunks).
  set(HIL_CONFIG_MCAP_DEPS "find_dependency(ZLIB)\n_hil_pkg(ZSTD libzstd)\n_hil_pkg(LZ4 liblz4)")
  string(APPEND HIL_PC_REQUIRES " zlib libzstd liblz4")
endif()

set(HIL_EXPORTED_TARGETS "")
set(_hil_header_dirs "")
while(_hil_exports)
  list(POP_FRONT _hil_exports target name)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  target_compile_features(${target} INTERFACE cxx_std_20)  # the headers use C++20
  if(HIL_SANITIZE)
    # Instrumented archives need the runtime in whatever links them, and consumers compiled the
    # same way: Eigen allocates differently under ASan (it does not trust malloc's alignment), so
    # an uninstrumented consumer would free a library's vector with the wrong call (found by the
    # ASan run of install.package).
    target_compile_options(${target} INTERFACE $<INSTALL_INTERFACE:-fsanitize=${HIL_SANITIZE}>)
    target_link_options(${target} INTERFACE $<INSTALL_INTERFACE:-fsanitize=${HIL_SANITIZE}>)
  endif()
  list(APPEND HIL_EXPORTED_TARGETS ${target})
  get_target_property(dir ${target} SOURCE_DIR)
  if(IS_DIRECTORY ${dir}/include)
    list(APPEND _hil_header_dirs ${dir}/include/)
  endif()
endwhile()
list(REMOVE_DUPLICATES _hil_header_dirs)

# The generated headers include each other by bare name ("std_msgs.h"), as does hil/dds/types.hpp:
# they go into one folder that is on the include path of hil::idl_types.
get_target_property(_hil_idl_bin hil_idl_types BINARY_DIR)
target_include_directories(hil_idl_types SYSTEM INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/hil/idl>)

# Two components: `runtime` (the command, the Python module, the profiles, examples and licence)
# and `devel` (libraries, headers, the CMake and pkg-config files). `cmake --install build
# --component runtime --strip` is what a lab machine that only runs hil needs (docs/install.md).
install(TARGETS ${HIL_EXPORTED_TARGETS} EXPORT hilTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT devel
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT devel
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
# `--strip` strips executables and modules only; the archives carry most of a RelWithDebInfo
# install's size (debug info), so they lose their debug sections as well.
foreach(target IN LISTS HIL_EXPORTED_TARGETS)
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "STATIC_LIBRARY" AND CMAKE_STRIP)
    install(CODE "if(CMAKE_INSTALL_DO_STRIP)
  execute_process(COMMAND \"${CMAKE_STRIP}\" --strip-debug \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/$<TARGET_FILE_NAME:${target}>\" COMMAND_ERROR_IS_FATAL ANY)
endif()" COMPONENT devel)
  endif()
endforeach()
install(DIRECTORY ${_hil_header_dirs} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT devel
  FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h")
install(DIRECTORY ${_hil_idl_bin}/generated/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hil/idl COMPONENT devel
  FILES_MATCHING PATTERN "*.h")

set(HIL_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/hil)
install(EXPORT hilTargets NAMESPACE hil:: DESTINATION ${HIL_CMAKE_DIR} COMPONENT devel)
set(HIL_INSTALL_DATA_DIR ${CMAKE_INSTALL_DATADIR}/hil)  # hil_DATA_DIR for consumers
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/hilConfig.cmake.in ${PROJECT_BINARY_DIR}/hilConfig.cmake
  INSTALL_DESTINATION ${HIL_CMAKE_DIR} PATH_VARS HIL_INSTALL_DATA_DIR)
# 0.x: a new minor version may break the interfaces.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/hilConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/hilConfig.cmake ${PROJECT_BINARY_DIR}/hilConfigVersion.cmake
  DESTINATION ${HIL_CMAKE_DIR} COMPONENT devel)

# pkg-config: static archives need dependents before dependencies on the link line, so the -l list
# is the exported targets in reverse topological order of their links.
function(_hil_visit target)
  get_property(seen GLOBAL PROPERTY _hil_seen_${target})
  if(seen)
    return()
  endif()
  set_property(GLOBAL PROPERTY _hil_seen_${target} TRUE)
  get_target_property(links ${target} LINK_LIBRARIES)
  foreach(link IN LISTS links)
    if(TARGET ${link})
      get_target_property(real ${link} ALIASED_TARGET)
      if(NOT real)
        set(real ${link})
      endif()
      if(real IN_LIST HIL_EXPORTED_TARGETS)
        _hil_visit(${real})
      endif()
    endif()
  endforeach()
  get_property(order GLOBAL PROPERTY _hil_link_order)
  set_property(GLOBAL PROPERTY _hil_link_order ${target} ${order})
endfunction()
foreach(target IN LISTS HIL_EXPORTED_TARGETS)
  _hil_visit(${target})
endforeach()
get_property(_hil_order GLOBAL PROPERTY _hil_link_order)
set(HIL_PC_LIBS "")
set(HIL_PC_CFLAGS "")
if(HIL_SANITIZE)
  set(HIL_PC_LIBS " -fsanitize=${HIL_SANITIZE}")
  set(HIL_PC_CFLAGS " -fsanitize=${HIL_SANITIZE}")
endif()
foreach(target IN LISTS _hil_order)
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "INTERFACE_LIBRARY")
    continue()  # header-only (hil::so3): nothing to link
  endif()
  get_target_property(out ${target} OUTPUT_NAME)
  if(NOT out)
    set(out ${target})
  endif()
  string(APPEND HIL_PC_LIBS " -l${out}")
endforeach()
# hil::format's URDF reader: kdl_parser has no usable .pc on Debian 12 (its Requires need ROS).
string(APPEND HIL_PC_LIBS " -lkdl_parser")
# The .pc file finds the prefix from its own place, so an installed tree can be moved.
file(RELATIVE_PATH HIL_PC_TO_PREFIX /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
string(REGEX REPLACE "/$" "" HIL_PC_TO_PREFIX "${HIL_PC_TO_PREFIX}")
configure_file(${CMAKE_CURRENT_LIST_DIR}/hil.pc.in ${PROJECT_BINARY_DIR}/hil.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/hil.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT devel)

# Data: the examples (`hil demo` finds them through tools/hil/data_dir.cpp) and the licence.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${HIL_INSTALL_DATA_DIR}/examples COMPONENT runtime
  PATTERN "__pycache__" EXCLUDE)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)
