# Included after project(native-shaderc) (see shaderc.cmake); the deferred call
# runs once the top-level CMakeLists.txt has added every subdirectory.
function(hybrid_rt_trim_shaderc)
  foreach(t SPIRV-Tools-shared SPIRV-Tools-reduce SPIRV-Tools-lint SPIRV-Tools-diff SPIRV-Tools-link)
    if(TARGET ${t})
      set_target_properties(${t} PROPERTIES EXCLUDE_FROM_ALL TRUE)
    endif()
  endforeach()
endfunction()
cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL hybrid_rt_trim_shaderc)
