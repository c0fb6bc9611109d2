/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_candump.h
 * @brief Host library: write and parse `candump -L` log lines, and a CAN port
 *        that writes them to a FILE*.
 *
 * Line format (can-utils candump -L / canplayer):
 *
 *     (1700000000.000000) vcan0 123#DEADBEEF
 *     (0000000001.250000) vcan0 000006A0#0011223344556677
 *
 * 3 hex digits = 11-bit standard identifier, 8 hex digits = 29-bit extended
 * identifier; data: 0 to 8 octets as hex pairs. Remote, error and CAN FD
 * frames are not classic data frames and are reported as errors.
 */
#ifndef IMEST_CANDUMP_H
#define IMEST_CANDUMP_H

#include <stddef.h>
#include <stdio.h>

#include "imest/imest_can.h"

#ifdef __cplusplus
extern "C" {
#endif

#define IMEST_CANDUMP_IFNAMSIZ 16 /**< as Linux IFNAMSIZ, including the NUL */
#define IMEST_CANDUMP_LINE_MAX 64 /**< longest formatted line + NUL */

/** Format one line (no newline). t_s: timestamp in seconds (negative or
 *  non-finite -> 0), printed with microseconds. iface NULL -> "vcan0".
 *  @return characters written (excluding NUL), or -1 if buf is too small or
 *  the frame is invalid (dlc > 8, identifier out of range). */
int imest_candump_format(char *buf, size_t n, double t_s, const char *iface, const imest_can_frame_t *f);

/** Results of imest_candump_parse(). */
#define IMEST_CANDUMP_OK    0    /**< a frame */
#define IMEST_CANDUMP_EMPTY 1    /**< blank line: nothing to do */
#define IMEST_CANDUMP_ERROR (-1) /**< malformed: *err says why */

/**
 * Parse one line (a trailing newline / CR is accepted).
 * @param t_s   (optional) timestamp
 * @param iface (optional) interface name, IMEST_CANDUMP_IFNAMSIZ chars
 * @param err   (optional) static message on IMEST_CANDUMP_ERROR
 */
int imest_candump_parse(const char *line, double *t_s, char iface[IMEST_CANDUMP_IFNAMSIZ],
                        imest_can_frame_t *f, const char **err);

/** A port that writes every frame as one line to a FILE*. */
typedef struct imest_candump_port {
  imest_can_port_t port; /**< pass &p.port to imest_can_pub_init() */
  FILE *fp;
  char iface[IMEST_CANDUMP_IFNAMSIZ];
  double t_s;           /**< timestamp of the next lines */
  unsigned long lines;  /**< lines written */
  unsigned long failed; /**< frames that could not be written */
} imest_candump_port_t;

/** Set up p to write to fp (not closed by this library) with interface name
 *  iface (NULL -> "vcan0"; at most 15 characters, no blanks). Timestamp 0
 *  until imest_candump_port_set_time(). @return 0, or -1 on bad arguments. */
int imest_candump_port_open(imest_candump_port_t *p, FILE *fp, const char *iface);

/** Timestamp of the following lines, e.g. the window's t_end_s (or an epoch
 *  offset + t_end_s). */
void imest_candump_port_set_time(imest_candump_port_t *p, double t_s);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_CANDUMP_H */
