# Checks that each layer of the library includes only the layers below it (CONTRIBUTING.md).
#
#   cmake -DSOURCE_DIR=<repository> -P tests/check_layers.cmake
#
# A layer is a folder of include/hssbem/ and src/; allowed_<layer> lists the layers its files may
# include ("hssbem/<layer>/..."). A folder without a rule fails the check too: a new layer (a
# format, say) gets its line here.
cmake_minimum_required(VERSION 3.20)

set(allowed_core      core)
set(allowed_mesh      core mesh)
set(allowed_bem       core mesh bem)
set(allowed_post      core mesh bem post)
set(allowed_interior  core mesh bem post interior)
set(allowed_compress  core mesh bem compress)
set(allowed_hss       core mesh bem compress hss)
set(allowed_h2        core mesh bem compress h2)
set(allowed_h2factor  core mesh bem compress h2 h2factor)
set(allowed_problem   core mesh bem problem)
set(allowed_io        core io)
set(allowed_reference core mesh bem compress h2 h2factor reference)
set(allowed_scene     core mesh bem post compress h2 h2factor reference scene)
set(allowed_contact   core mesh bem post reference contact)
set(allowed_petsc     core mesh bem compress hss h2 h2factor reference scene petsc)
set(allowed_session   core mesh bem post interior compress hss h2 h2factor reference scene contact problem io petsc session)
set(allowed_app       core mesh bem post interior compress hss h2 h2factor reference scene contact problem io petsc session app)
set(allowed_apps     petsc app)

# Headers kept at a file's former path after it moved up into session/, so that programs that
# include them still build: each holds comments, #pragma once and one include of its new home
# under hssbem/session/, and nothing else.
set(forwarding_headers include/hssbem/scene/scene.hpp include/hssbem/contact/contact_scene.hpp)

if(NOT SOURCE_DIR)
  message(FATAL_ERROR "give -DSOURCE_DIR=<repository>")
endif()
file(GLOB_RECURSE files RELATIVE ${SOURCE_DIR}
     ${SOURCE_DIR}/include/hssbem/*.h ${SOURCE_DIR}/include/hssbem/*.hpp
     ${SOURCE_DIR}/src/*.h ${SOURCE_DIR}/src/*.hpp ${SOURCE_DIR}/src/*.cpp ${SOURCE_DIR}/src/*.cxx)
set(errors "")
set(checked 0)
foreach(f IN LISTS files)
  if(NOT f MATCHES "^(include/hssbem|src)/([^/]+)/")
    string(APPEND errors "\n  ${f}: outside every layer folder")
    continue()
  endif()
  set(layer ${CMAKE_MATCH_2})
  if(NOT DEFINED allowed_${layer})
    string(APPEND errors "\n  ${f}: layer '${layer}' has no rule in tests/check_layers.cmake")
    continue()
  endif()
  math(EXPR checked "${checked} + 1")
  if(f IN_LIST forwarding_headers)
    file(STRINGS ${SOURCE_DIR}/${f} code REGEX "^[ \t]*[^/ \t]")
    if(NOT code MATCHES "^#pragma once;#include \"hssbem/session/[a-z_]+\\.hpp\"$")
      string(APPEND errors "\n  ${f}: a forwarding header holds only #pragma once and one include of hssbem/session/ (found: ${code})")
    endif()
    continue()
  endif()
  file(STRINGS ${SOURCE_DIR}/${f} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<]hssbem/")
  foreach(line IN LISTS lines)
    if(line MATCHES "hssbem/([^/\">]+)/" AND NOT CMAKE_MATCH_1 IN_LIST allowed_${layer})
      string(STRIP "${line}" line)
      string(APPEND errors "\n  ${f}: ${line} (${layer}/ may include ${allowed_${layer}})")
    endif()
  endforeach()
endforeach()
if(errors)
  message(FATAL_ERROR "layer violations:${errors}")
endif()
message(STATUS "layers: ${checked} files include only the layers below them")
