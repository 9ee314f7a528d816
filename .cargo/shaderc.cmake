# CMake toolchain file for shaderc-sys's from-source build, set through
# .cargo/config.toml. shaderc-sys builds CMake's `install` target, i.e.
# everything; it links only libshaderc_combined.a (shaderc + glslang +
# SPIRV-Tools + SPIRV-Tools-opt). Measured on the 2-core CI VM: see
# bench/results/ci-build-time.md.

# -O1: a third less compile time than CMake's Release -O3; glslang and the
# SPIR-V optimizer run only in build.rs, on a few dozen shaders. (Cache
# entries: CMake appends its -O3 to a *_INIT value, but keeps a cached one.)
set(CMAKE_C_FLAGS_RELEASE "-O1 -DNDEBUG" CACHE STRING "")
set(CMAKE_CXX_FLAGS_RELEASE "-O1 -DNDEBUG" CACHE STRING "")

# The examples are not linked. (glslc stays: shaderc installs it even when
# told to skip executables, and fails without it.)
set(SHADERC_SKIP_EXAMPLES ON CACHE BOOL "")
# SPIRV-Tools' own install rules would install the libraries left out below;
# libshaderc_combined.a carries every object shaderc needs.
set(SKIP_SPIRV_TOOLS_INSTALL ON CACHE BOOL "")

# After the top-level project has added every target: take the SPIRV-Tools
# libraries shaderc does not link out of `all` (the shared library compiles
# all of SPIRV-Tools a second time).
set(CMAKE_PROJECT_native-shaderc_INCLUDE "${CMAKE_CURRENT_LIST_DIR}/shaderc-trim.cmake")
