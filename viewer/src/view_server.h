// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/view_server.h -- penumbra-view's HTTP server: the page and one database's files
#pragma once
#include <filesystem>
#include <cstddef>
#include <memory>
#include <string>

#include "spacemouse_mapping.h"

namespace penumbra::viewer {

struct ViewOptions {
  std::filesystem::path database;  ///< a Cinema spec D directory (data.csv and images)
  std::string host = "127.0.0.1";  ///< the address to listen on
  int port = 0;                    ///< 0: a free port
  std::string token;               ///< empty: a new random one (session_token.h)
  /// The run's store and the config it ran with (empty: the one the store keeps): views it never
  /// stored are rendered from them (render_routes.h). No store: the database's images only.
  std::string store, config;
  std::size_t render_queue = 8;  ///< render requests that may wait at once
  bool event_stream = true;      ///< serve /events (the 3D mouse's events and status)
};

/// Serves, to requests that carry the session token (a `token` query parameter, or the cookie
/// the page's first request sets): the page at `/`, its files at `/assets/NAME`, the database's
/// files at `/db/PATH` (only regular files inside the database: request_path.h), `/api/info`,
/// with a store /api/store and /api/render (render_routes.h), and, where `event_stream` is on,
/// `/events`: what publish() and publish_status() send, as server-sent events to at most
/// EventHub::kMaxSubscribers pages at once (503 beyond). Anything else, or a request without the
/// token, gets 404 or 403 and nothing of the database. Every response forbids other origins'
/// scripts and sends no referrer, so the token does not leave the page.
class ViewServer {
public:
  /// Listens (on a free port when `port` is 0). Throws penumbra::Error(io_error) when the
  /// database is not a directory or the address cannot be bound.
  explicit ViewServer(ViewOptions options);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  int port() const;
  const std::string& token() const;
  /// What a person opens: http://HOST:PORT/?token=TOKEN.
  std::string url() const;
  /// Serves until stop() (from another thread or a signal handler's thread).
  void run();
  void stop();

  /// To every page listening on /events, as {"type":"motion",...} (event_hub.h); from any thread.
  void publish(const ViewEvent& event);
  /// To every page listening on /events and to each that opens later, as {"type":"status",...}.
  void publish_status(const std::string& message);
  /// How many pages listen on /events.
  std::size_t listeners() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// `penumbra-view --export DB`: the page and its files written into the database (index.html,
/// viewer/...), reading the database's files beside it, so that any static file server shows it.
/// Writes through temporary files renamed into place; throws penumbra::Error(io_error).
void export_page(const std::filesystem::path& database);

}  // namespace penumbra::viewer
