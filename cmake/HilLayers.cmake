# hil's layers (docs/architecture.md), checked when the build is configured.
#
# Every target the project defines carries a layer (hil_layer(target LAYER)); the targets under
# tests/ take `tests` unless they say otherwise. hil_check_project_layers() then walks every
# target of the tree and stops the configuration when
#   - a target has no layer, or one that is not in the table below;
#   - a target reaches, directly or through any chain of links (generator expressions such as
#     $<BUILD_INTERFACE:...> or $<LINK_ONLY:...> unwrapped), a target of a layer its own may not
#     link; the message names the chain.
# It also writes hil_layers.json into the build folder for the include-level check
# (tests/architecture/check_includes.py): headers and sources obey the same table.
include_guard(GLOBAL)

# layer: the layers it may link. A layer absent from its own list may not link its own kind
# (commands share code through the modules, never through each other).
set(HIL_LAYER_RULES
  "core:core"
  "numerics:core,numerics"
  "bus:core,bus"
  "devices:core,devices"
  "formats:core,numerics,bus,formats"
  "acquisition:core,numerics,bus,devices,formats,acquisition"
  "services:core,numerics,bus,formats,services"
  "framework:core,bus,framework"
  "commands:core,numerics,bus,devices,formats,acquisition,services,framework"
  "program:core,numerics,bus,devices,formats,acquisition,services,framework,commands,program"
  "bindings:core,numerics,formats,services,bindings"
  "tests:core,numerics,bus,devices,formats,acquisition,services,framework,tests")

# Imported libraries that belong to a layer: Fast DDS is the bus's, libmodbus the devices', the
# YAML parser the formats', CLI11 the command framework's. Others (Eigen, spdlog, JSON, zlib,
# GoogleTest, ...) may be linked from anywhere.
set(HIL_EXTERNAL_LAYERS
  "fastrtps:bus" "fastcdr:bus" "PkgConfig::MODBUS:devices" "yaml-cpp:formats" "CLI11::CLI11:framework")

define_property(TARGET PROPERTY HIL_LAYER BRIEF_DOCS "hil's layer of the target" FULL_DOCS "cmake/HilLayers.cmake")
define_property(DIRECTORY PROPERTY HIL_DEFAULT_LAYER INHERITED
  BRIEF_DOCS "layer of the targets below a folder that set none (tests/ only)" FULL_DOCS "cmake/HilLayers.cmake")

# hil_layer(target layer)
function(hil_layer target layer)
  set_property(TARGET ${target} PROPERTY HIL_LAYER ${layer})
endfunction()

function(_hil_allowed layer out)
  set(result "")
  set(found FALSE)
  foreach(rule IN LISTS HIL_LAYER_RULES)
    string(REPLACE ":" ";" parts "${rule}")
    list(GET parts 0 name)
    if(name STREQUAL layer)
      list(GET parts 1 allowed)
      string(REPLACE "," ";" result "${allowed}")
      set(found TRUE)
    endif()
  endforeach()
  set(${out} "${result}" PARENT_SCOPE)
  set(${out}_KNOWN ${found} PARENT_SCOPE)
endfunction()

# The layer of target `t` (a real, not an alias, name) into `out`: its HIL_LAYER, the tests
# default, the table of imported libraries, or "" (unclassified; for imported targets: free).
function(_hil_layer_of t out)
  get_target_property(layer ${t} HIL_LAYER)
  if(NOT layer)
    set(layer "")
    get_target_property(imported ${t} IMPORTED)
    if(imported)
      foreach(entry IN LISTS HIL_EXTERNAL_LAYERS)
        string(FIND "${entry}" ":" colon REVERSE)
        string(SUBSTRING "${entry}" 0 ${colon} name)
        math(EXPR start "${colon} + 1")
        string(SUBSTRING "${entry}" ${start} -1 l)
        if(name STREQUAL t)
          set(layer ${l})
        endif()
      endforeach()
    else()
      get_target_property(dir ${t} SOURCE_DIR)
      get_property(default DIRECTORY ${dir} PROPERTY HIL_DEFAULT_LAYER)
      # The default applies under tests/ only: a module cannot take a layer from its folder.
      if(default AND dir MATCHES "^${PROJECT_SOURCE_DIR}/tests(/|$)")
        set(layer ${default})
      endif()
    endif()
  endif()
  set(${out} "${layer}" PARENT_SCOPE)
endfunction()

# The target names in one link item: itself, or every target named inside a generator expression
# ($<BUILD_INTERFACE:x>, $<LINK_ONLY:x>, $<$<CONFIG:Debug>:x>, ...). Directory markers (::@...) and
# plain files or flags give nothing.
function(_hil_link_item_targets item out)
  set(result "")
  if(item MATCHES "^::@")
    # cross-directory link marker
  elseif(item MATCHES "\\$<")
    string(REGEX MATCHALL "[A-Za-z0-9_.+-]+(::[A-Za-z0-9_.+-]+)*" tokens "${item}")
    foreach(tok IN LISTS tokens)
      if(TARGET ${tok})
        list(APPEND result ${tok})
      endif()
    endforeach()
  elseif(TARGET ${item})
    set(result ${item})
  endif()
  set(${out} "${result}" PARENT_SCOPE)
endfunction()

function(_hil_real t out)
  get_target_property(real ${t} ALIASED_TARGET)
  if(real)
    set(t ${real})
  endif()
  set(${out} ${t} PARENT_SCOPE)
endfunction()

# The targets `target` reaches through links, as chains "a>b>c" (one per reached target).
function(_hil_link_closure target out)
  _hil_real(${target} target)
  set(seen "${target}")
  set(chains "")
  set(queue "${target}")
  set(chain_of_${target} "${target}")
  while(queue)
    list(POP_FRONT queue t)
    set(links "")
    get_target_property(type ${t} TYPE)
    if(NOT type STREQUAL "INTERFACE_LIBRARY" OR CMAKE_VERSION VERSION_GREATER_EQUAL 3.19)
      get_target_property(direct ${t} LINK_LIBRARIES)
      if(direct)
        list(APPEND links ${direct})
      endif()
    endif()
    get_target_property(iface ${t} INTERFACE_LINK_LIBRARIES)
    if(iface)
      list(APPEND links ${iface})
    endif()
    foreach(item IN LISTS links)
      _hil_link_item_targets("${item}" reached)
      foreach(l IN LISTS reached)
        _hil_real(${l} l)
        if(l IN_LIST seen)
          continue()
        endif()
        list(APPEND seen ${l})
        set(chain_of_${l} "${chain_of_${t}}>${l}")
        list(APPEND chains "${chain_of_${l}}")
        list(APPEND queue ${l})
      endforeach()
    endforeach()
  endwhile()
  set(${out} "${chains}" PARENT_SCOPE)
endfunction()

# Every target defined in `dir` and the directories below it.
function(hil_targets_under dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(s IN LISTS subdirs)
    hil_targets_under(${s} more)
    list(APPEND targets ${more})
  endforeach()
  set(${out} "${targets}" PARENT_SCOPE)
endfunction()

# hil_check_project_layers([DIRECTORY dir] [JSON file]): checks every library and executable
# defined under `dir` (default: the project's top folder); FATAL_ERROR with every problem found.
function(hil_check_project_layers)
  cmake_parse_arguments(arg "" "DIRECTORY;JSON" "" ${ARGN})
  if(NOT arg_DIRECTORY)
    set(arg_DIRECTORY ${PROJECT_SOURCE_DIR})
  endif()
  if(NOT arg_JSON)
    set(arg_JSON ${PROJECT_BINARY_DIR}/hil_layers.json)
  endif()
  hil_targets_under(${arg_DIRECTORY} all)
  set(problems "")
  set(checked 0)
  set(json_targets "")
  set(sep "")
  foreach(t IN LISTS all)
    get_target_property(type ${t} TYPE)
    if(NOT type MATCHES "^(STATIC_LIBRARY|SHARED_LIBRARY|MODULE_LIBRARY|OBJECT_LIBRARY|INTERFACE_LIBRARY|EXECUTABLE)$")
      continue()  # custom targets (generators, test fixtures) link nothing
    endif()
    math(EXPR checked "${checked} + 1")
    _hil_layer_of(${t} layer)
    get_target_property(dir ${t} SOURCE_DIR)
    file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${dir}/CMakeLists.txt)
    if(layer STREQUAL "")
      list(APPEND problems "${t} (${rel}) has no layer: add hil_layer(${t} <layer>) with one of the layers of cmake/HilLayers.cmake")
      continue()
    endif()
    _hil_allowed(${layer} allowed)
    if(NOT allowed_KNOWN)
      list(APPEND problems "${t} (${rel}) has the layer '${layer}', which is not one of cmake/HilLayers.cmake's")
      continue()
    endif()
    string(APPEND json_targets "${sep}\n    {\"name\": \"${t}\", \"layer\": \"${layer}\", \"source_dir\": \"${dir}\"}")
    set(sep ",")
    _hil_link_closure(${t} chains)
    foreach(c IN LISTS chains)
      string(REGEX REPLACE "^.*>" "" last "${c}")
      _hil_layer_of(${last} last_layer)
      if(last_layer STREQUAL "" OR last_layer IN_LIST allowed)
        continue()  # free imported libraries; unclassified project targets are reported on their own
      endif()
      string(REPLACE ">" " -> " c "${c}")
      list(APPEND problems "${t} (${layer}) may not link ${last} (${last_layer}): ${c}")
    endforeach()
  endforeach()

  set(json_rules "")
  set(sep "")
  foreach(rule IN LISTS HIL_LAYER_RULES)
    string(REPLACE ":" ";" parts "${rule}")
    list(GET parts 0 name)
    list(GET parts 1 allowed)
    string(REPLACE "," "\", \"" allowed "${allowed}")
    string(APPEND json_rules "${sep}\n    \"${name}\": [\"${allowed}\"]")
    set(sep ",")
  endforeach()
  file(WRITE ${arg_JSON} "{\n  \"source_dir\": \"${PROJECT_SOURCE_DIR}\",\n  \"rules\": {${json_rules}\n  },\n  \"targets\": [${json_targets}\n  ]\n}\n")

  if(problems)
    list(JOIN problems "\n  " text)
    message(FATAL_ERROR "hil's layers (docs/architecture.md, cmake/HilLayers.cmake) are broken:\n  ${text}")
  endif()
  message(STATUS "hil layers: ${checked} targets checked")
endfunction()
