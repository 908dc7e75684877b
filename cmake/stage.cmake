# meniscus_stage_tree(<source dir> <target dir> <out var> [EXCLUDE names...]): copies the .py and .toml files of a
# source tree into the build tree (rebuilt when a source changes) and returns the staged paths in <out var>.
function(meniscus_stage_tree source target out_var)
  cmake_parse_arguments(STAGE "" "" "EXCLUDE" ${ARGN})
  file(GLOB_RECURSE files CONFIGURE_DEPENDS RELATIVE ${source} ${source}/*.py ${source}/*.toml ${source}/*.pyi
       ${source}/py.typed)
  set(staged)
  foreach(file ${files})
    if(file IN_LIST STAGE_EXCLUDE)
      continue()
    endif()
    add_custom_command(OUTPUT ${target}/${file}
                       COMMAND ${CMAKE_COMMAND} -E copy ${source}/${file} ${target}/${file}
                       DEPENDS ${source}/${file})
    list(APPEND staged ${target}/${file})
  endforeach()
  set(${out_var} ${staged} PARENT_SCOPE)
endfunction()
