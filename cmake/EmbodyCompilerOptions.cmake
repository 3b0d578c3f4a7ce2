# Warnings for our own code; third-party headers come in as SYSTEM includes via imported targets.
# (Installed as embody::warnings only because static libraries name their private dependencies
# in their link interface; it adds nothing to a consumer's link.)
add_library(embody_warnings INTERFACE)
# -Wno-missing-field-initializers: the Vulkan/OpenXR idiom `VkFooInfo info{VK_STRUCTURE_TYPE_FOO}`
# value-initialises the rest on purpose.
target_compile_options(embody_warnings INTERFACE -Wall -Wextra -Wpedantic -Wno-missing-field-initializers)
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  # GCC 12 false positive on `"literal" + std::string` at -O2 (GCC bug 105651).
  target_compile_options(embody_warnings INTERFACE -Wno-restrict)
  if(EMBODY_PCH)
    # With precompiled headers GCC 12 inlines libstdc++'s string copies differently and reports
    # its known false positives there (GCC bugs 105651, 105746, 106199: memcpy "out of bounds" in
    # char_traits.h for `vec.push_back("literal")` and `"a" + std::string(b)`), in files that
    # compile clean without them. -DEMBODY_PCH=OFF keeps all three warnings.
    target_compile_options(embody_warnings INTERFACE -Wno-array-bounds -Wno-stringop-overflow -Wno-stringop-overread)
  endif()
endif()
if(EMBODY_WERROR)
  target_compile_options(embody_warnings INTERFACE -Werror)
endif()

# Wider SIMD for Eigen (AVX2 + FMA with x86-64-v3 or native): 8 % off the fast IK pass, a third
# off the reference pass (docs/performance.md). Off by default so binaries run on any x86-64; set
# it when building for the machine (or the fleet) that runs the headset.
if(EMBODY_ARCH)
  add_compile_options(-march=${EMBODY_ARCH})
endif()

if(EMBODY_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
if(EMBODY_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "EMBODY_FUZZ needs clang (libFuzzer): cmake -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang")
  endif()
  # Every library is instrumented for coverage; the fuzz executables add -fsanitize=fuzzer (main).
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
if(EMBODY_TSAN)
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
endif()

# Unity builds (EMBODY_UNITY, on by default): each target's .cpp files are compiled 8 to a
# translation unit, so the Eigen, GLM and JSON templates they share are instantiated and
# optimised once per batch instead of once per file: a fresh `CI=1 make test` on the 2-core
# machine 15 min 49 s -> 10 min 11 s (2026-11-27). Files in one batch share one scope: names
# in a file's anonymous namespace must not repeat in another file of the same target (the same
# signature is a redefinition error; the same name with other parameters can silently become an
# overload of the other file's: name helpers for what they do, keep one of each).
# -DEMBODY_UNITY=OFF compiles file by file (quicker incremental rebuilds of one file; the check
# that each file stands alone). The libFuzzer build (`make fuzz`, its own folder, a target per
# reader) stays file by file.
if(EMBODY_UNITY AND NOT EMBODY_FUZZ)
  set(CMAKE_UNITY_BUILD ON)
  set(CMAKE_UNITY_BUILD_BATCH_SIZE 8)
endif()

# Precompiled headers (EMBODY_PCH, on by default): a translation unit at -O2 on the 2-core CI
# machine spends ~1.8 s parsing Catch2, ~2.0 s Eigen/Dense and ~2.5 s nlohmann/json before its
# own code, in ~250 files. Each target parses its headers once: a fresh -j2 build took 12 min 50 s
# instead of 14 min 28 s (2026-11-26; the rest is the files' own templates and optimisation).
# The lists name only headers the target's dependencies already provide.
# -DEMBODY_PCH=OFF builds without (a check that every file includes what it uses).
set(EMBODY_PCH_IK <vector> <string> <memory> <Eigen/Dense>)
set(EMBODY_PCH_BODY ${EMBODY_PCH_IK} <glm/glm.hpp> <glm/gtc/quaternion.hpp>)
function(embody_precompile target)
  if(EMBODY_PCH)
    target_precompile_headers(${target} PRIVATE ${ARGN})
  endif()
endfunction()

# embody_library(NAME DIRS dir... LIBS lib... [PCH header...]): a static library from every .cpp in the given
# folders (non-recursive), so adding a file to a folder needs no CMake edit. It is also installed
# (docs/api.md): the library, the folders' headers under include/embody/<dir>/ (so the same
# `#include "ik/solver.h"` works), and the target exported as embody::<NAME without embody_>.
function(embody_library name)
  cmake_parse_arguments(ARG "" "" "DIRS;LIBS;PRIVATE_LIBS;PCH" ${ARGN})
  set(srcs)
  foreach(d IN LISTS ARG_DIRS)
    file(GLOB s CONFIGURE_DEPENDS "${CMAKE_SOURCE_DIR}/${d}/*.cpp")
    list(APPEND srcs ${s})
  endforeach()
  if(NOT srcs)  # a folder not written yet: keep the target so dependants still configure
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE "$<BUILD_INTERFACE:${CMAKE_SOURCE_DIR}>")
    target_link_libraries(${name} INTERFACE ${ARG_LIBS})
  else()
    add_library(${name} STATIC ${srcs})
    target_include_directories(${name} PUBLIC "$<BUILD_INTERFACE:${CMAKE_SOURCE_DIR}>")
    target_link_libraries(${name} PUBLIC ${ARG_LIBS} PRIVATE embody_warnings ${ARG_PRIVATE_LIBS})
    if(ARG_PCH)
      embody_precompile(${name} ${ARG_PCH})
    endif()
  endif()
  embody_install_library(${name} DIRS ${ARG_DIRS})
endfunction()

# embody_install_library(NAME [DIRS dir...]): installs a library target into the `embody` export
# set (embody::<NAME without embody_>) with the headers of DIRS (cmake/EmbodyInstall.cmake
# writes embodyConfig.cmake).
function(embody_install_library name)
  cmake_parse_arguments(ARG "" "" "DIRS" ${ARGN})
  string(REGEX REPLACE "^embody_" "" exportName "${name}")
  set_target_properties(${name} PROPERTIES EXPORT_NAME ${exportName})
  target_include_directories(${name} INTERFACE "$<INSTALL_INTERFACE:include/embody>")
  install(TARGETS ${name} EXPORT embodyTargets ARCHIVE DESTINATION lib)
  foreach(d IN LISTS ARG_DIRS)
    file(GLOB headers "${CMAKE_SOURCE_DIR}/${d}/*.h")
    install(FILES ${headers} DESTINATION include/embody/${d})
  endforeach()
endfunction()
