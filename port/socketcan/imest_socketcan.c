/* SPDX-License-Identifier: Apache-2.0 */
/* SocketCAN (Linux CAN_RAW) port. */
#define _GNU_SOURCE 1
#include "imest_socketcan.h"

#include <errno.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>

static int fail(imest_socketcan_t *sc, int e, const char *fmt, const char *a)
{
  sc->last_errno = e;
  snprintf(sc->err, sizeof sc->err, fmt, a, strerror(e));
  return -e;
}

static int sc_send(void *ctx, const imest_can_frame_t *f)
{
  imest_socketcan_t *sc = (imest_socketcan_t *)ctx;
  struct can_frame cf;
  unsigned int i;
  ssize_t n;
  if (sc == NULL || sc->fd < 0 || f == NULL || f->dlc > 8u) {
    if (sc != NULL) sc->failed++;
    return -1;
  }
  memset(&cf, 0, sizeof cf);
  if (f->id & IMEST_CAN_ID_EXT) {
    cf.can_id = (canid_t)((f->id & CAN_EFF_MASK) | CAN_EFF_FLAG);
  } else {
    cf.can_id = (canid_t)(f->id & CAN_SFF_MASK);
  }
  cf.can_dlc = (__u8)f->dlc;
  for (i = 0u; i < f->dlc; i++) cf.data[i] = (__u8)(f->data[i] & 0xFFu);
  n = send(sc->fd, &cf, sizeof cf, MSG_DONTWAIT);
  if (n != (ssize_t)sizeof cf) {
    int e = n < 0 ? errno : EIO;
    sc->failed++;
    fail(sc, e, "send on %s: %s", sc->ifname);
    return -1;
  }
  sc->sent++;
  return 0;
}

int imest_socketcan_open(imest_socketcan_t *sc, const char *ifname)
{
  struct sockaddr_can addr;
  struct ifreq ifr;
  unsigned int idx;
  int fd;
  if (sc == NULL) {
    return -EINVAL;
  }
  memset(sc, 0, sizeof *sc);
  sc->fd = -1;
  sc->port.send = sc_send;
  sc->port.ctx = sc;
  if (ifname == NULL || ifname[0] == '\0' || strlen(ifname) >= sizeof sc->ifname ||
      strlen(ifname) >= IFNAMSIZ) {
    sc->last_errno = EINVAL;
    snprintf(sc->err, sizeof sc->err, "invalid CAN interface name '%s' (1 to %d characters)",
             ifname ? ifname : "(null)", IFNAMSIZ - 1);
    return -EINVAL;
  }
  strcpy(sc->ifname, ifname); // NOLINT(clang-analyzer-security.insecureAPI.strcpy): length checked above

  fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) {
    int e = errno;
    if (e == EAFNOSUPPORT || e == EPROTONOSUPPORT) {
      return fail(sc, e,
                  "cannot open a CAN socket for '%s': this kernel has no SocketCAN support "
                  "(socket(AF_CAN, SOCK_RAW, CAN_RAW): %s); load the modules can and can-raw "
                  "(modprobe can-raw) or use a kernel with CONFIG_CAN_RAW",
                  ifname);
    }
    return fail(sc, e, "cannot open a CAN socket for '%s': %s", ifname);
  }
  idx = if_nametoindex(ifname);
  if (idx == 0u) {
    int e = errno;
    close(fd);
    if (e == ENODEV || e == ENXIO) {
      return fail(sc, ENODEV,
                  "no such network interface '%s' (%s); for a virtual bus: "
                  "ip link add dev vcan0 type vcan && ip link set up vcan0",
                  ifname);
    }
    return fail(sc, e, "cannot look up interface '%s': %s", ifname);
  }
  memset(&addr, 0, sizeof addr);
  addr.can_family = AF_CAN;
  addr.can_ifindex = (int)idx;
  if (bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
    int e = errno;
    close(fd);
    if (e == ENODEV) {
      return fail(sc, e, "interface '%s' is not a CAN interface (%s)", ifname);
    }
    return fail(sc, e, "cannot bind a CAN socket to '%s': %s", ifname);
  }
  memset(&ifr, 0, sizeof ifr);
  strcpy(ifr.ifr_name, ifname); // NOLINT(clang-analyzer-security.insecureAPI.strcpy): length checked at open
  if (ioctl(fd, SIOCGIFFLAGS, &ifr) == 0 && !(ifr.ifr_flags & IFF_UP)) {
    close(fd);
    fail(sc, ENETDOWN, "CAN interface '%s' is down (%s)", ifname);
    snprintf(sc->err + strlen(sc->err), sizeof sc->err - strlen(sc->err), ": ip link set up %s", ifname);
    return -ENETDOWN;
  }
  sc->fd = fd;
  sc->ifindex = (int)idx;
  return 0;
}

int imest_socketcan_recv(imest_socketcan_t *sc, imest_can_frame_t *f, int timeout_ms, double *t_s)
{
  struct pollfd pfd;
  struct can_frame cf;
  struct timespec ts;
  ssize_t n;
  int r;
  unsigned int i;
  if (sc == NULL || f == NULL || sc->fd < 0) {
    return -EINVAL;
  }
  for (;;) {
    pfd.fd = sc->fd;
    pfd.events = POLLIN;
    pfd.revents = 0;
    r = poll(&pfd, 1, timeout_ms);
    if (r < 0) {
      if (errno == EINTR) return 0;
      return fail(sc, errno, "poll on %s: %s", sc->ifname);
    }
    if (r == 0) return 0;
    n = recv(sc->fd, &cf, sizeof cf, 0);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) return 0;
      return fail(sc, errno, "receive on %s: %s", sc->ifname);
    }
    if (n != (ssize_t)sizeof cf) continue;                   /* CAN FD or short */
    if (cf.can_id & (CAN_RTR_FLAG | CAN_ERR_FLAG)) continue; /* not a data frame */
    if (cf.can_id & CAN_EFF_FLAG) {
      f->id = (uint32_t)(cf.can_id & CAN_EFF_MASK) | IMEST_CAN_ID_EXT;
    } else {
      f->id = (uint32_t)(cf.can_id & CAN_SFF_MASK);
    }
    f->dlc = cf.can_dlc > 8u ? 8u : cf.can_dlc;
    for (i = 0u; i < 8u; i++) f->data[i] = i < f->dlc ? cf.data[i] : 0u;
    if (t_s != NULL) {
      clock_gettime(CLOCK_REALTIME, &ts);
      *t_s = (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
    }
    return 1;
  }
}

void imest_socketcan_close(imest_socketcan_t *sc)
{
  if (sc != NULL && sc->fd >= 0) {
    close(sc->fd);
    sc->fd = -1;
  }
}
