// SPDX-License-Identifier: BSD-3-Clause
/* examples/using-cmake/main.c -- proves the installed package links: prints the version and
 * checks that a bad config comes back as an error status, not an abort. */
#include <stdio.h>

#include "penumbra/penumbra.h"

int main(void) {
  pnb_context ctx = NULL;
  const pnb_status s = pnb_create("{\"not a config\": true}", &ctx);
  printf("Penumbra %s: bad config -> status %d (%s)\n", pnb_version(), (int)s, pnb_last_error(NULL));
  pnb_destroy(ctx);
  return s == PNB_INVALID_ARGUMENT ? 0 : 1;
}
