// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/version.cpp
#include "penumbra/penumbra.h"

extern "C" const char* pnb_version(void) { return "0.1.0"; }
