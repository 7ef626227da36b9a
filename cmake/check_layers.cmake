# The layers of Kaskad and what each may use, and a check that the build and the sources keep to
# them. Run as a test (CTest `layer_check`, label unit):
#   cmake -DSOURCE_DIR=<repo> -DEDGES=<build>/kaskad_link_edges.txt -P cmake/check_layers.cmake
# EDGES is written at configure time by kaskad_write_link_edges() (top-level CMakeLists.txt): one
# "target dependency" line per direct link of our library targets (LINK_LIBRARIES and
# INTERFACE_LINK_LIBRARIES, aliases resolved). The check fails when
#   1. a target links a layer it may not use (a lower layer linking a higher one, or a sibling),
#   2. a source file includes a header of a layer it may not use (header-only leaks the link
#      graph cannot see, e.g. a components/ header including runtime/render/),
#   3. the table itself is not ordered (every layer uses only layers listed before it, and
#      everything they use): so the allowed graph, and with it the real one, has no cycle.

cmake_minimum_required(VERSION 3.25)

# Layers, lowest first; kaskad_<layer> is the CMake target (cli: the `kaskad` executable). A file's
# layer is its folder: runtime/<layer>/, components/ or systems/.
set(layers result fields core ecs components math gpu features assets reference render systems app cli)
# What each layer may use, directly or through another layer (so: closed under "uses").
set(uses_result     "")
set(uses_fields     "")
set(uses_core       fields result)
set(uses_ecs        result)
set(uses_components ecs fields result)
set(uses_math       components ecs fields result)
set(uses_gpu        core fields result)
set(uses_features   components ecs core fields result)
set(uses_assets     features math components ecs core fields result)
set(uses_reference  assets features math components ecs core fields result)
set(uses_render     assets features math gpu components ecs core fields result)
set(uses_systems    render math assets features gpu components ecs core fields result)
set(uses_app        systems render reference math assets features gpu components ecs core fields result)
set(uses_cli        app systems render reference math assets features gpu components ecs core fields result)

# The layer of a source file, from its path relative to the repository ("" when none).
function(layer_of path out)
  set(layer "")
  if(path MATCHES "^runtime/([a-z]+)/")
    set(layer ${CMAKE_MATCH_1})
  elseif(path MATCHES "^(components|systems)/")
    set(layer ${CMAKE_MATCH_1})
  endif()
  set(${out} "${layer}" PARENT_SCOPE)
endfunction()

set(errors "")

# 3. The table is ordered and closed.
set(seen "")
foreach(layer IN LISTS layers)
  foreach(used IN LISTS uses_${layer})
    if(NOT used IN_LIST seen)
      list(APPEND errors "table: ${layer} uses ${used}, which is not listed before it")
    endif()
    foreach(indirect IN LISTS uses_${used})
      if(NOT indirect IN_LIST uses_${layer})
        list(APPEND errors "table: ${layer} uses ${used}, which uses ${indirect}: list it for ${layer}")
      endif()
    endforeach()
  endforeach()
  list(APPEND seen ${layer})
endforeach()

# 1. Link edges of the build.
if(NOT EXISTS "${EDGES}")
  message(FATAL_ERROR "EDGES file '${EDGES}' not found (it is written when the build is configured)")
endif()
file(STRINGS "${EDGES}" edge_lines)
set(edge_count 0)
foreach(line IN LISTS edge_lines)
  if(NOT line MATCHES "^kaskad_([a-z_]+) kaskad_([a-z_]+)$")
    list(APPEND errors "${EDGES}: unreadable line '${line}'")
    continue()
  endif()
  set(from ${CMAKE_MATCH_1})
  set(to ${CMAKE_MATCH_2})
  math(EXPR edge_count "${edge_count} + 1")
  if(NOT from IN_LIST layers OR NOT to IN_LIST layers)
    list(APPEND errors "link: kaskad_${from} -> kaskad_${to}: a target not in the layer table")
  elseif(NOT to IN_LIST uses_${from})
    list(APPEND errors "link: kaskad_${from} -> kaskad_${to}: ${from} may not use ${to}")
  endif()
endforeach()

# 2. Include lines of the sources.
file(GLOB_RECURSE sources RELATIVE "${SOURCE_DIR}"
     "${SOURCE_DIR}/runtime/*.h" "${SOURCE_DIR}/runtime/*.cpp"
     "${SOURCE_DIR}/components/*.h" "${SOURCE_DIR}/components/*.cpp"
     "${SOURCE_DIR}/systems/*.h" "${SOURCE_DIR}/systems/*.cpp")
set(include_count 0)
foreach(file IN LISTS sources)
  layer_of("${file}" from)
  file(STRINGS "${SOURCE_DIR}/${file}" includes REGEX "^[ \t]*#[ \t]*include[ \t]+\"")
  foreach(line IN LISTS includes)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]+\"([^\"]+)\".*$" "\\1" header "${line}")
    layer_of("${header}" to)
    if(to STREQUAL "" OR to STREQUAL from)
      continue()
    endif()
    math(EXPR include_count "${include_count} + 1")
    if(NOT to IN_LIST uses_${from})
      list(APPEND errors "include: ${file} (${from}) includes ${header} (${to}): ${from} may not use ${to}")
    endif()
  endforeach()
endforeach()

if(errors)
  list(JOIN errors "\n  " text)
  message(FATAL_ERROR "layer check failed (table in cmake/check_layers.cmake):\n  ${text}")
endif()
list(LENGTH sources file_count)
message(STATUS "layers ok: ${edge_count} link edges, ${include_count} cross-layer includes in ${file_count} files")
