/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_version.h
 * The library's version: the one place it is written (CMakeLists.txt reads it).
 * Semantic versioning: a MAJOR change breaks the API or the CAN frames
 * (tools/imest.dbc).
 */
#ifndef IMEST_IMEST_VERSION_H
#define IMEST_IMEST_VERSION_H

#define IMEST_VERSION_MAJOR  0
#define IMEST_VERSION_MINOR  1
#define IMEST_VERSION_PATCH  0
/** "MAJOR.MINOR.PATCH" */
#define IMEST_VERSION_STRING "0.1.0"
/** One number for compile-time comparisons: MAJOR * 10000 + MINOR * 100 + PATCH. */
#define IMEST_VERSION        (IMEST_VERSION_MAJOR * 10000 + IMEST_VERSION_MINOR * 100 + IMEST_VERSION_PATCH)

#endif /* IMEST_IMEST_VERSION_H */
