/* SPDX-License-Identifier: Apache-2.0 */
/* Marker functions: each is a single "bx lr" at its own address. The counting
 * plugin opens a channel when fw_mark_bN executes and closes it at fw_mark_eN. */
  .syntax unified
  .thumb
  .section .text.harness.markers, "ax", %progbits
  .macro MARK name
  .global \name
  .type \name, %function
  .thumb_func
  .align 2
\name:
  bx lr
  .size \name, . - \name
  .endm
  MARK fw_mark_b0
  MARK fw_mark_e0
  MARK fw_mark_b1
  MARK fw_mark_e1
  MARK fw_mark_b2
  MARK fw_mark_e2
  MARK fw_mark_b3
  MARK fw_mark_e3
  MARK fw_mark_b4
  MARK fw_mark_e4
  MARK fw_mark_b5
  MARK fw_mark_e5
