# Checks that dependencies point down: no file of a layer includes a header of a higher layer,
# and nothing below src/idmpc/mujoco includes a MuJoCo header. Layers, lowest first:
#   spatial < model < dynamics < ocp < solver < experiment < mujoco < render < app
# (src/idmpc/<layer>/…; app is src/app and src/app_main). Relative includes that leave a layer's
# directory ("../…") are violations too.
#
#   cmake -DIDMPC_SOURCE_DIR=<project dir> -P cmake/check_layering.cmake
#
# Prints one line per violation and "<k> layering violation(s)", and fails, if there are any.

if(NOT IDMPC_SOURCE_DIR)
  message(FATAL_ERROR "usage: cmake -DIDMPC_SOURCE_DIR=<project dir> -P check_layering.cmake")
endif()

set(layers spatial model dynamics ocp solver experiment mujoco render app)
list(FIND layers mujoco mujoco_rank)

# the directories of each layer, relative to IDMPC_SOURCE_DIR/src
function(layer_dirs layer out)
  if(layer STREQUAL "app")
    set(${out} app app_main PARENT_SCOPE)
  else()
    set(${out} idmpc/${layer} PARENT_SCOPE)
  endif()
endfunction()

set(violations 0)
set(checked 0)
foreach(layer IN LISTS layers)
  list(FIND layers ${layer} rank)
  layer_dirs(${layer} dirs)
  foreach(dir IN LISTS dirs)
    file(GLOB_RECURSE files ${IDMPC_SOURCE_DIR}/src/${dir}/*.hpp ${IDMPC_SOURCE_DIR}/src/${dir}/*.cpp
         ${IDMPC_SOURCE_DIR}/src/${dir}/*.h ${IDMPC_SOURCE_DIR}/src/${dir}/*.cc)
    foreach(file IN LISTS files)
      math(EXPR checked "${checked} + 1")
      file(RELATIVE_PATH where ${IDMPC_SOURCE_DIR} ${file})
      file(STRINGS ${file} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
      foreach(line IN LISTS lines)
        string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]*)[>\"].*$" "\\1" header "${line}")
        set(problem "")
        if(header MATCHES "^idmpc/([^/]+)/")
          set(target ${CMAKE_MATCH_1})
          list(FIND layers ${target} target_rank)
          if(target_rank LESS 0 OR target STREQUAL "app")
            set(problem "idmpc/${target} is not a layer")
          elseif(target_rank GREATER rank)
            set(problem "${layer} may not include the higher layer ${target}")
          endif()
        elseif(header MATCHES "^(app|app_main)/" AND NOT layer STREQUAL "app")
          set(problem "${layer} may not include the higher layer app")
        elseif(header MATCHES "^mujoco[/.]" AND rank LESS mujoco_rank)
          set(problem "${layer} may not include MuJoCo (only mujoco/ and above may)")
        elseif(header MATCHES "(^|/)\\.\\./")
          set(problem "relative include out of the layer's directory")
        endif()
        if(problem)
          message("${where}: #include ${header}: ${problem}")
          math(EXPR violations "${violations} + 1")
        endif()
      endforeach()
    endforeach()
  endforeach()
endforeach()

if(checked EQUAL 0)
  message(FATAL_ERROR "no source file found under ${IDMPC_SOURCE_DIR}/src")
endif()
if(violations GREATER 0)
  message(FATAL_ERROR "${violations} layering violation(s) in ${checked} files")
endif()
message("layering: ${checked} files, every include points down")
