/* SPDX-License-Identifier: Apache-2.0 */
// The translation unit that builds GoogleTest's precompiled header (test/CMakeLists.txt).
#include <gtest/gtest.h>
