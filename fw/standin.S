/* SPDX-License-Identifier: Apache-2.0 */
/* Stand-in with a known instruction count, to validate the counting method:
 * fw_standin(n), n >= 1, executes exactly 3 + 3 n instructions (including its
 * bx lr) and returns n (n + 1) / 2. */
  .syntax unified
  .thumb
  .text
  .global fw_standin
  .type fw_standin, %function
  .thumb_func
  .align 2
fw_standin:
  movs r1, #0
1:
  adds r1, r1, r0
  subs r0, r0, #1
  bne 1b
  mov r0, r1
  bx lr
  .size fw_standin, . - fw_standin
