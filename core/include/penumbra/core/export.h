// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/export.h -- what the shared libraries export
//
// The libraries are built with hidden visibility: only what a public header declares between
// PNB_PUBLIC_BEGIN and PNB_PUBLIC_END is exported. Everything declared only under a module's src/
// stays inside its library; tests reach it through the module's internal target.
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define PNB_PUBLIC_BEGIN _Pragma("GCC visibility push(default)")
#define PNB_PUBLIC_END _Pragma("GCC visibility pop")
#else
#define PNB_PUBLIC_BEGIN
#define PNB_PUBLIC_END
#endif
