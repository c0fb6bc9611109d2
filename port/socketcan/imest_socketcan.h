/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_socketcan.h
 * @brief Host library (Linux): a CAN port on a SocketCAN CAN_RAW socket.
 *
 *     imest_socketcan_t sc;
 *     if (imest_socketcan_open(&sc, "vcan0") != 0) { puts(sc.err); ... }
 *     imest_can_pub_init(&pub, &sc.port, IMEST_CAN_DEFAULT_BASE_ID);
 *     ...
 *     imest_socketcan_close(&sc);
 *
 * Sending never blocks (MSG_DONTWAIT): a full queue (ENOBUFS/EAGAIN) or a
 * down interface is a failed send, counted by the publisher (pub.tx_failed).
 */
#ifndef IMEST_SOCKETCAN_H
#define IMEST_SOCKETCAN_H

#include <stdint.h>

#include "imest/imest_can.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct imest_socketcan {
  imest_can_port_t port; /**< pass &sc.port to imest_can_pub_init() */
  int fd;                /**< CAN_RAW socket, -1 when closed */
  int ifindex;
  char ifname[16];
  int last_errno; /**< errno of the last failure (open, send, recv) */
  char err[256];  /**< human-readable message of the last failure */
  unsigned long sent;
  unsigned long failed;
} imest_socketcan_t;

/**
 * Open a CAN_RAW socket bound to interface `ifname` (e.g. "can0", "vcan0").
 * @return 0, or -errno with sc->err explaining, e.g.
 *   -EAFNOSUPPORT: the kernel has no CAN support (modules can, can-raw),
 *   -ENODEV: no such interface, or it is not a CAN interface,
 *   -ENETDOWN: the interface is down.
 */
int imest_socketcan_open(imest_socketcan_t *sc, const char *ifname);

/** Receive one frame, waiting at most timeout_ms (< 0: forever). Remote,
 *  error and CAN FD frames are skipped. t_s (optional): receive time
 *  (CLOCK_REALTIME, seconds). @return 1 frame, 0 timeout / interrupted,
 *  -errno on error (sc->err set). */
int imest_socketcan_recv(imest_socketcan_t *sc, imest_can_frame_t *f, int timeout_ms, double *t_s);

/** Close the socket (safe to call twice). */
void imest_socketcan_close(imest_socketcan_t *sc);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_SOCKETCAN_H */
