/* SPDX-License-Identifier: Apache-2.0 */
/* imest-replay's advice: a setting the estimator refuses, or a record whose
 * windows all fail for one reason, turned into what is wrong with the data
 * or the options and what to do (docs/feeding-logs.md has the long form). */
#ifndef IMEST_REPLAY_ADVICE_H
#define IMEST_REPLAY_ADVICE_H

#include "imest/imest.h"
#include "replay_options.h"
#include "replay_scan.h"

/* Explains why imest_config_check() refused `field` for this record. Returns
 * the exit code: TOOL_EXIT_USAGE if an option the user gave is at fault,
 * TOOL_EXIT_DATA if the record (its sample rate) is. */
int replay_explain_config(const replay_opts_t *o, const replay_scan_t *s, const imest_config_t *cfg,
                          const char *field);

/* What to check when every window of a record ends with this status (NULL if
 * there is nothing to say). */
const char *replay_remedy(int status);

#endif
