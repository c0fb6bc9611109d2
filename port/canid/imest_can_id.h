/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_can_id.h
 * @brief Host tools: one parser for the CAN base identifier given on a
 *        command line (--can-base-id of imest-monitor and imest-replay, the
 *        test publisher), so every tool takes the same spellings.
 *
 *   "0x6A0", "1696"      11-bit standard identifier (default kind up to 0x7FF)
 *   "0x18FF5000"         above 0x7FF: a 29-bit extended identifier, automatically
 *   "0x100" + force_ext  a small number as a 29-bit extended identifier (--can-ext)
 *   "0x98FF5000"         bit 31 set (Linux CAN_EFF_FLAG, imest's IMEST_CAN_ID_EXT):
 *                        the extended identifier 0x18FF5000, as older scripts wrote it
 *
 * The node sends IMEST_CAN_NFRAMES frames at base .. base + IMEST_CAN_NFRAMES - 1,
 * so the last of them must still be an identifier of the same kind.
 */
#ifndef IMEST_CAN_ID_H
#define IMEST_CAN_ID_H

#include <stddef.h>
#include <stdint.h>

#include "imest/imest_can.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Parse a base identifier.
 * @param text        the option's value
 * @param force_ext   nonzero: extended even if the number fits 11 bits
 * @param ext_option  the tool's name for force_ext (e.g. "--can-ext"), used in messages
 * @param base_id     receives the identifier, | IMEST_CAN_ID_EXT when extended
 * @param err, n      receive a message naming the problem and the remedy on error
 * @retval IMEST_OK        parsed
 * @retval IMEST_ERR_NULL  text, ext_option or base_id is NULL
 * @retval IMEST_ERR_ARG   not a number, negative, or out of range (*err says why)
 */
int imest_can_id_parse(const char *text, int force_ext, const char *ext_option, uint32_t *base_id, char *err,
                       size_t n);

/** Format an identifier as candump does: 3 hex digits for 11-bit, 8 for
 *  29-bit, with "0x" (e.g. "0x6A0", "0x18FF5000"). @return buf */
const char *imest_can_id_format(uint32_t id, char *buf, size_t n);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_CAN_ID_H */
