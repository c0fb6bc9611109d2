/* SPDX-License-Identifier: Apache-2.0 */
/* imest-sim entry point; everything is in imsim_cli.c. */
#include "imsim_cli.h"

int main(int argc, char **argv)
{
  return imsim_cli_main(argc, argv);
}
