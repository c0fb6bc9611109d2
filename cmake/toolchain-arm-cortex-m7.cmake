# SPDX-License-Identifier: Apache-2.0
# Cross toolchain: arm-none-eabi, Cortex-M7 with double-precision FPU (FPv5-D16,
# hard-float ABI).
#   cmake --preset m7      (or -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-arm-cortex-m7.cmake)
set(IMEST_ARM_CPU_FLAGS "-mthumb -mcpu=cortex-m7 -mfpu=fpv5-d16 -mfloat-abi=hard")
set(IMEST_ARM_TARGET_NAME m7)
include(${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake)
