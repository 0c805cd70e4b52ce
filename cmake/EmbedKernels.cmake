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

# Embeds one file (the viewer's page, host/view/viewer.html) as `const std::string& NAMESPACE::FUNCTION()`, declared
# in HEADER; regenerated whenever the file changes. The page is served from the binary: no file or CDN at run time.
set(MIPNERF_EMBED_FILE_SCRIPT "${CMAKE_CURRENT_LIST_DIR}/embed_file_script.cmake")
function(mipnerf_embed_file out_var input header namespace function)
  get_filename_component(stem "${input}" NAME_WE)
  set(generated "${CMAKE_CURRENT_BINARY_DIR}/generated/embedded_${stem}.cpp")
  add_custom_command(
    OUTPUT "${generated}"
    COMMAND ${CMAKE_COMMAND} -DINPUT=${input} -DOUTPUT=${generated} -DHEADER=${header} -DNAMESPACE=${namespace}
            -DFUNCTION=${function} -P "${MIPNERF_EMBED_FILE_SCRIPT}"
    DEPENDS "${input}" "${MIPNERF_EMBED_FILE_SCRIPT}"
    COMMENT "Embedding ${input}"
    VERBATIM)
  set(${out_var} "${generated}" PARENT_SCOPE)
endfunction()
