# SPDX-License-Identifier: Apache-2.0
# Common part of the arm-none-eabi toolchain files (included by
# toolchain-arm-cortex-m4f.cmake and toolchain-arm-cortex-m7.cmake, which set
# IMEST_ARM_CPU_FLAGS first). Bare metal: no OS, no malloc, no stdio.
#
# Flags chosen for the core:
#   -O2                     optimisation of the ISR path for every figure in
#                           fw/README.md (src/CMakeLists.txt builds the
#                           once-per-window stages with -Os)
#   -ffreestanding          no hosted environment assumed (__STDC_HOSTED__ == 0)
#   -fbuiltin               ...but let GCC expand the <math.h> calls of the core
#                           (fabsf, fabs, sqrt, fmin, fmax, isfinite ...) into FPU
#                           instructions; -ffreestanding alone implies
#                           -fno-builtin, which turns every fabsf() into a call
#                           (measured: +6 % instructions per solve on the M7).
#                           Set IMEST_ARM_BUILTINS=OFF to measure without it.
#   -fno-math-errno         sqrt() need not set errno (so it can be one vsqrt)
#   -ffunction-sections -fdata-sections, linked with --gc-sections
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(IMEST_ARM_PREFIX arm-none-eabi- CACHE STRING "prefix of the cross tools")
set(CMAKE_C_COMPILER   ${IMEST_ARM_PREFIX}gcc)
set(CMAKE_CXX_COMPILER ${IMEST_ARM_PREFIX}g++)
set(CMAKE_ASM_COMPILER ${IMEST_ARM_PREFIX}gcc)
set(CMAKE_AR           ${IMEST_ARM_PREFIX}ar CACHE FILEPATH "")
set(CMAKE_RANLIB       ${IMEST_ARM_PREFIX}ranlib CACHE FILEPATH "")
set(CMAKE_SIZE         ${IMEST_ARM_PREFIX}size CACHE FILEPATH "")
set(CMAKE_OBJDUMP      ${IMEST_ARM_PREFIX}objdump CACHE FILEPATH "")

# Compiler checks link a static library, not an executable (no startup code yet).
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(IMEST_ARM_BUILTIN_FLAG "")
if(NOT DEFINED IMEST_ARM_BUILTINS OR IMEST_ARM_BUILTINS)
  set(IMEST_ARM_BUILTIN_FLAG "-fbuiltin")
endif()
set(CMAKE_C_FLAGS_INIT
    "${IMEST_ARM_CPU_FLAGS} -ffreestanding ${IMEST_ARM_BUILTIN_FLAG} -fno-math-errno -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT "${IMEST_ARM_CPU_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_ASM_FLAGS_INIT "${IMEST_ARM_CPU_FLAGS}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${IMEST_ARM_CPU_FLAGS} -nostartfiles -Wl,--gc-sections")

# -O2 in every build type that optimises. As cache entries, because CMake
# appends its own defaults (-O3 for Release) to the *_INIT values.
set(CMAKE_C_FLAGS_RELEASE "-O2 -DNDEBUG" CACHE STRING "C flags for Release (imest firmware: -O2)")
set(CMAKE_C_FLAGS_RELWITHDEBINFO "-O2 -g -DNDEBUG" CACHE STRING "C flags for RelWithDebInfo")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
