// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/compression.h -- everything a consumer needs:
//   StreamingEncoder   in situ: push(time, values) each step, finish() at the end
//   CompressedField    open a field file, random access to any step (read_step)
//   Pager              sequential playback with the next page prefetched
//   encode_window / decode_step / decode_window / decode_vertex   the codec itself
//   StepCursor         O(1) sequential steps of any page (the pager holds one)
#pragma once
#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/encoded_page.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/lbg.h"
#include "penumbra/compression/pager.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/compression/version.h"
#include "penumbra/compression/window_codec.h"
