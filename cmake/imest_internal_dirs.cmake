# SPDX-License-Identifier: Apache-2.0
# The core's internal header folders, in one place: src/CMakeLists.txt gives
# them to the library (and, as imest_internal, to the tests of its stages);
# fuzz/CMakeLists.txt, a project of its own, includes this file too.
# IMEST_SRC_ROOT: the checkout's src/ folder.
set(IMEST_INTERNAL_DIRS
  ${IMEST_SRC_ROOT}
  ${IMEST_SRC_ROOT}/estimator/isr
  ${IMEST_SRC_ROOT}/estimator/solve
  ${IMEST_SRC_ROOT}/estimator/window
  ${IMEST_SRC_ROOT}/commission
  ${IMEST_SRC_ROOT}/commission/fits)
