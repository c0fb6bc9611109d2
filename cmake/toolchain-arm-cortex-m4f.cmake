# SPDX-License-Identifier: Apache-2.0
# Cross toolchain: arm-none-eabi, Cortex-M4F (single-precision FPU, hard-float ABI).
#   cmake --preset m4      (or -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-arm-cortex-m4f.cmake)
set(IMEST_ARM_CPU_FLAGS "-mthumb -mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
set(IMEST_ARM_TARGET_NAME m4)
include(${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake)
