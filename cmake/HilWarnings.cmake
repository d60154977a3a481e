# Project-wide warning flags, applied per target with hil_target_warnings().
add_library(hil_warnings INTERFACE)
hil_layer(hil_warnings core)  # compiler flags only: every layer uses them
target_compile_options(hil_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Woverloaded-virtual
  -Wformat=2 -Wimplicit-fallthrough)
if(HIL_WERROR)
  target_compile_options(hil_warnings INTERFACE -Werror)
endif()

# BUILD_INTERFACE: a static library's private links go into its export; the flags must not.
function(hil_target_warnings target)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:hil_warnings>)
endfunction()
