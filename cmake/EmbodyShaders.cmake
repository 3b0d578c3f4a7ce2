# embody_add_shaders(TARGET name SOURCES a.vert b.frag ...): compiles GLSL to SPIR-V with
# glslangValidator (--target-env vulkan1.3) at build time and embeds each as a C array in a
# generated header <stem>_<stage>.spv.h (array name <stem>_<stage>_spv). A shader error fails the build.
# Shared GLSL snippets (*.glsl beside a shader, pulled in with GL_GOOGLE_include_directive) are
# dependencies of every shader in that folder, so editing one recompiles its users.
find_program(GLSLANG_VALIDATOR glslangValidator REQUIRED)
function(embody_add_shaders)
  cmake_parse_arguments(ARG "" "TARGET" "SOURCES" ${ARGN})
  set(outdir "${CMAKE_BINARY_DIR}/generated/shaders")
  file(MAKE_DIRECTORY "${outdir}")
  set(headers)
  foreach(src IN LISTS ARG_SOURCES)
    get_filename_component(abs "${src}" ABSOLUTE)
    get_filename_component(stem "${src}" NAME_WE)
    get_filename_component(ext "${src}" LAST_EXT)
    string(SUBSTRING "${ext}" 1 -1 stage)
    set(var "${stem}_${stage}_spv")
    set(out "${outdir}/${stem}_${stage}.spv.h")
    get_filename_component(srcdir "${abs}" DIRECTORY)
    file(GLOB includes CONFIGURE_DEPENDS "${srcdir}/*.glsl")
    add_custom_command(
      OUTPUT "${out}"
      COMMAND ${GLSLANG_VALIDATOR} --quiet -V --target-env vulkan1.3 --vn ${var} -o "${out}" "${abs}"
      DEPENDS "${abs}" ${includes}
      COMMENT "glslang ${src}"
      VERBATIM)
    list(APPEND headers "${out}")
  endforeach()
  add_custom_target(${ARG_TARGET}_compile DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_compile)
  target_include_directories(${ARG_TARGET} INTERFACE "$<BUILD_INTERFACE:${CMAKE_BINARY_DIR}/generated>")
endfunction()
