# Embeds kernels/*.cl into the library as named strings, regenerated whenever a .cl file changes.
# The .cl files stay plain OpenCL C (each compiles on its own); only the generated file wraps them.

set(MIPNERF_EMBED_SCRIPT "${CMAKE_CURRENT_LIST_DIR}/embed_kernels_script.cmake")

function(mipnerf_embed_kernels out_var kernel_dir)
  file(GLOB kernel_files CONFIGURE_DEPENDS "${kernel_dir}/*.cl")
  list(SORT kernel_files)
  set(generated "${CMAKE_CURRENT_BINARY_DIR}/generated/embedded_kernels.cpp")
  add_custom_command(
    OUTPUT "${generated}"
    COMMAND ${CMAKE_COMMAND} -DKERNEL_DIR=${kernel_dir} -DOUTPUT=${generated}
            -P "${MIPNERF_EMBED_SCRIPT}"
    DEPENDS ${kernel_files} "${MIPNERF_EMBED_SCRIPT}"
    COMMENT "Embedding OpenCL kernels from ${kernel_dir}"
    VERBATIM)
  set(${out_var} "${generated}" PARENT_SCOPE)
endfunction()
