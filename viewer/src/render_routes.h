// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/render_routes.h -- the HTTP interface to views rendered from a run's store
#pragma once
#include <httplib.h>

#include <string>

#include "render_queue.h"

namespace penumbra::viewer {

/// The request a query string asks for (step, field, phi, theta, zoom, lit, and tf: JSON
/// {"colors": [[x, r, g, b], ...], "opacities": [[x, a], ...]} in the units of the run's
/// config). Throws Error(invalid_argument) naming the parameter that is missing or malformed.
ViewRequest view_request(const httplib::Params& params);

/// The store's steps, fields, transfer functions and image size as JSON, for the page.
std::string store_info_json(const StoreInfo& info);

/// Adds GET /api/store (store_info_json) and GET /api/render?... to `server`: a PNG rendered
/// through `queue` (headers X-Penumbra-Load-Ms, -Light-Ms, -Render-Ms), 400 for a bad request,
/// 409 when the same page's newer request superseded it (parameter `client`), 503 when the queue
/// is full, 500 when rendering failed; every refusal says why in plain text. The routes rely on
/// the server's pre-routing handler for the session token.
void add_render_routes(httplib::Server& server, RenderQueue& queue);

}  // namespace penumbra::viewer
