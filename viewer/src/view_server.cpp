// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/view_server.cpp -- routes, the token check, files served from inside the database
#include "view_server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <fstream>
#include <sstream>

#include "assets.h"
#include "event_hub.h"
#include "penumbra/core/error.h"
#include "render_routes.h"
#include "request_path.h"
#include "session_token.h"

namespace penumbra::viewer {
namespace {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

void write_atomically(const std::filesystem::path& path, const std::string& content) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << content;
    out.flush();
    if (!out) throw Error(ErrorCode::io_error, "penumbra-view: cannot write '" + tmp.string() + "'");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(ErrorCode::io_error, "penumbra-view: cannot rename '" + tmp.string() + "': " + ec.message());
}

// The value of cookie `name` in a Cookie header, or "".
std::string cookie(const httplib::Request& req, const std::string& name) {
  const std::string header = req.get_header_value("Cookie");
  std::istringstream parts(header);
  for (std::string part; std::getline(parts, part, ';');) {
    const auto start = part.find_first_not_of(' ');
    if (start == std::string::npos) continue;
    part = part.substr(start);
    if (part.rfind(name + "=", 0) == 0) return part.substr(name.size() + 1);
  }
  return "";
}

// How long a stream waits for an event before it checks its page, and how many such waits pass
// before it writes a comment: writing is how a page that went away is noticed.
constexpr std::chrono::milliseconds kEventWait{1000};
constexpr int kWaitsPerKeepAlive = 2;

void secure_headers(httplib::Response& res) {
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_header("Referrer-Policy", "no-referrer");
  res.set_header("Content-Security-Policy", "default-src 'self'; img-src 'self' blob: data:; frame-ancestors 'none'");
  res.set_header("Cache-Control", "no-store");
}

}  // namespace

struct ViewServer::Impl {
  ViewOptions options;
  std::filesystem::path root;
  httplib::Server server;
  int port = 0;
  std::string cookie_name;
  socket_t listening_socket = INVALID_SOCKET;
  std::unique_ptr<RenderQueue> renders;  ///< with a store only
  EventHub events;

  bool allowed(const httplib::Request& req) const {
    const std::string& t = options.token;
    return same_token(req.get_param_value("token"), t) || same_token(cookie(req, cookie_name), t);
  }
  void routes();
  void event_route();
};

void ViewServer::Impl::routes() {
  server.set_payload_max_length(64 * 1024);
  server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    secure_headers(res);
    if (req.method != "GET" && req.method != "HEAD") {
      res.status = 405;
      return httplib::Server::HandlerResponse::Handled;
    }
    if (req.path.size() > kMaxRequestPath + 8 || !allowed(req)) {
      res.status = req.path.size() > kMaxRequestPath + 8 ? 414 : 403;
      res.set_content(res.status == 403 ? "penumbra-view: open the URL that penumbra-view printed (it carries the session token)\n"
                                        : "penumbra-view: request path too long\n",
                      "text/plain");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  server.Get("/", [this](const httplib::Request& req, httplib::Response& res) {
    if (same_token(req.get_param_value("token"), options.token))
      res.set_header("Set-Cookie", cookie_name + "=" + options.token + "; HttpOnly; SameSite=Strict; Path=/");
    res.set_content(page("db/", "assets/", true, options.event_stream), "text/html; charset=utf-8");
  });
  server.Get(R"(/assets/([A-Za-z0-9_.-]+))", [](const httplib::Request& req, httplib::Response& res) {
    const Asset* a = find_asset(req.matches[1]);
    if (!a || a->name == "index.html") {
      res.status = 404;
      return;
    }
    res.set_content(a->content, media_type(a->name));
  });
  server.Get(R"(/db/(.*))", [this](const httplib::Request& req, httplib::Response& res) {
    // The raw target, so that an encoded ".." is seen as the client sent it.
    std::string target = req.target.substr(4);
    target = target.substr(0, target.find('?'));
    const auto file = resolve_in(root, target);
    if (!file) {
      res.status = 404;
      res.set_content("penumbra-view: no such file in the database\n", "text/plain");
      return;
    }
    res.set_content(read_file(*file), media_type(file->string()));
  });
  server.Get("/api/info", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content("{\"database\": \"" + root.filename().string() + "\", \"store\": " + (renders ? "true" : "false") + "}",
                    "application/json");
  });
  if (options.event_stream) event_route();
}

// Each page's stream holds one of the server's threads while it is open: the pool has one more
// thread for each page that may listen, so files are still served.
void ViewServer::Impl::event_route() {
  server.new_task_queue = [] { return new httplib::ThreadPool(CPPHTTPLIB_THREAD_POOL_COUNT + EventHub::kMaxSubscribers); };
  server.Get("/events", [this](const httplib::Request&, httplib::Response& res) {
    auto subscriber = events.subscribe();
    if (!subscriber) {
      res.status = 503;
      res.set_content("penumbra-view: " + std::to_string(EventHub::kMaxSubscribers) + " pages already receive events\n", "text/plain");
      return;
    }
    // Exactly this media type: cpp-httplib compresses other text types, which would hold events back.
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, subscriber, quiet = 0](std::size_t, httplib::DataSink& sink) mutable {
          std::optional<std::string> text = events.next(*subscriber, kEventWait);
          if (!text) return false;
          if (text->empty()) {
            if (++quiet < kWaitsPerKeepAlive) return sink.is_writable();
            *text = ":\n\n";
          }
          quiet = 0;
          return sink.write(text->data(), text->size());
        },
        [this, subscriber](bool) { events.unsubscribe(subscriber); });
  });
}

ViewServer::ViewServer(ViewOptions options) : m_impl(std::make_unique<Impl>()) {
  Impl& im = *m_impl;
  im.options = std::move(options);
  if (im.options.token.empty()) im.options.token = new_token();
  std::error_code ec;
  if (!std::filesystem::is_directory(im.options.database, ec))
    throw Error(ErrorCode::io_error, "penumbra-view: '" + im.options.database.string() + "' is not a directory");
  im.root = std::filesystem::canonical(im.options.database, ec);
  if (!im.options.store.empty()) {
    im.renders = std::make_unique<RenderQueue>(std::make_unique<StoreView>(im.options.store, im.options.config),
                                               im.options.render_queue);
  }
  im.routes();
  if (im.renders) add_render_routes(im.server, *im.renders);
  im.server.set_socket_options([&im](socket_t sock) {
    httplib::default_socket_options(sock);
    im.listening_socket = sock;
  });
  im.port = im.options.port == 0 ? im.server.bind_to_any_port(im.options.host)
                                 : (im.server.bind_to_port(im.options.host, im.options.port) ? im.options.port : -1);
  if (im.port <= 0)
    throw Error(ErrorCode::io_error, "penumbra-view: cannot listen on " + im.options.host + ":" + std::to_string(im.options.port));
  // Debian's cpp-httplib listens with a backlog of 5, built into its library: a page preloading
  // its images, or a few browsers at once, connect faster than the workers accept, and the dropped
  // connections wait seconds for an answer. Listening again on the bound socket raises the backlog.
  if (im.listening_socket != INVALID_SOCKET) ::listen(im.listening_socket, SOMAXCONN);
  // Cookies ignore ports: each viewer on a host keeps its own.
  im.cookie_name = "pnb_view_" + std::to_string(im.port);
}

ViewServer::~ViewServer() { stop(); }

int ViewServer::port() const { return m_impl->port; }
const std::string& ViewServer::token() const { return m_impl->options.token; }

std::string ViewServer::url() const {
  const std::string& h = m_impl->options.host;
  const std::string host = h == "0.0.0.0" || h.empty() ? "127.0.0.1" : h;
  return "http://" + host + ":" + std::to_string(m_impl->port) + "/?token=" + m_impl->options.token;
}

void ViewServer::run() { m_impl->server.listen_after_bind(); }

// The streams end first: the server waits for its threads, which they hold.
void ViewServer::stop() {
  m_impl->events.close();
  m_impl->server.stop();
}

void ViewServer::publish(const ViewEvent& event) { m_impl->events.publish(event); }
void ViewServer::publish_status(const std::string& message) { m_impl->events.publish_status(message); }
std::size_t ViewServer::listeners() const { return m_impl->events.subscribers(); }

void export_page(const std::filesystem::path& database) {
  std::error_code ec;
  if (!std::filesystem::is_directory(database, ec))
    throw Error(ErrorCode::io_error, "penumbra-view --export: '" + database.string() + "' is not a directory");
  std::filesystem::create_directories(database / "viewer", ec);
  if (ec) throw Error(ErrorCode::io_error, "penumbra-view --export: cannot create '" + (database / "viewer").string() + "'");
  for (const Asset& a : assets())
    if (a.name != "index.html") write_atomically(database / "viewer" / a.name, a.content);
  write_atomically(database / "index.html", page("", "viewer/", false));
}

}  // namespace penumbra::viewer
