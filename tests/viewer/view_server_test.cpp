// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/view_server_test.cpp -- penumbra-view's server: only the session's requests, only
// files inside the database, the page exported for static servers
#include <gtest/gtest.h>
#include <unistd.h>
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "assets.h"
#include "event_hub.h"
#include "penumbra/core/error.h"
#include "request_path.h"
#include "session_token.h"
#include "view_server.h"

namespace penumbra::viewer {
namespace {

namespace fs = std::filesystem;

// A database directory with data.csv, one image in a subfolder, and a secret beside it.
struct Database {
  fs::path dir = fs::temp_directory_path() / ("pnb_view_test_" + std::to_string(::getpid()));
  fs::path db = dir / "db";
  Database() {
    fs::remove_all(dir);
    fs::create_directories(db / "T");
    std::ofstream(db / "data.csv") << "time,phi,theta,field,FILE\n0,30,20,T,T/a b.png\n";
    std::ofstream(db / "T" / "a b.png") << "not really a png";
    std::ofstream(dir / "secret.txt") << "secret";
    fs::create_symlink(dir / "secret.txt", db / "link-out.txt");
    fs::create_directories(dir / "outside");
    fs::create_directory_symlink(dir / "outside", db / "dir-out");
    std::ofstream(dir / "outside" / "x.csv") << "x";
  }
  ~Database() { fs::remove_all(dir); }
};

TEST(RequestPath, FilesInsideTheDatabaseOnly) {
  const Database d;
  EXPECT_TRUE(resolve_in(d.db, "data.csv"));
  EXPECT_TRUE(resolve_in(d.db, "T/a%20b.png"));
  EXPECT_EQ(resolve_in(d.db, "T/a%20b.png")->filename(), "a b.png");
  for (const std::string bad :
       {"", "..", "../secret.txt", "T/../../secret.txt", "%2e%2e/secret.txt", "%2E%2E%2Fsecret.txt", "T/%2e%2e/%2e%2e/secret.txt",
        "/etc/passwd", "%2fetc%2fpasswd", "T", "T/", "./data.csv", "T//a%20b.png", "link-out.txt", "dir-out/x.csv",
        "data.csv%00.png", "T\\a b.png", "T%5ca%20b.png", "%zz", "%2", "missing.png"})
    EXPECT_FALSE(resolve_in(d.db, bad)) << bad;
  EXPECT_FALSE(resolve_in(d.db, std::string(kMaxRequestPath + 1, 'a')));
}

TEST(RequestPath, PercentDecoding) {
  EXPECT_EQ(percent_decoded("a%20b%2F"), "a b/");
  EXPECT_FALSE(percent_decoded("a%0"));
  EXPECT_FALSE(percent_decoded("a%00b"));
  EXPECT_FALSE(percent_decoded("%g0"));
}

TEST(SessionToken, RandomAndComparedWhole) {
  const std::string a = new_token(), b = new_token();
  EXPECT_EQ(a.size(), 32u);
  EXPECT_NE(a, b);
  EXPECT_TRUE(same_token(a, a));
  EXPECT_FALSE(same_token(a.substr(0, 31), a));
  EXPECT_FALSE(same_token("", ""));
  std::string c = a;
  c[31] = c[31] == '0' ? '1' : '0';
  EXPECT_FALSE(same_token(c, a));
}

// A server on a free loopback port, running on its own thread.
struct Running {
  ViewServer server;
  std::thread thread;
  explicit Running(const fs::path& db, bool event_stream = true)
      : server(ViewOptions{.database = db, .event_stream = event_stream}), thread([this] { server.run(); }) {
    httplib::Client probe("127.0.0.1", server.port());
    for (int i = 0; i < 200 && !probe.Get("/"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ~Running() {
    server.stop();
    thread.join();
  }
  std::string with_token(const std::string& path) const { return path + "?token=" + server.token(); }
};

TEST(ViewServer, ServesTheSessionOnly) {
  const Database d;
  Running r(d.db);
  httplib::Client c("127.0.0.1", r.server.port());
  EXPECT_EQ(c.Get("/db/data.csv")->status, 403);
  EXPECT_EQ(c.Get("/db/data.csv?token=" + std::string(32, '0'))->status, 403);
  const auto csv = c.Get(r.with_token("/db/data.csv"));
  ASSERT_TRUE(csv);
  EXPECT_EQ(csv->status, 200);
  EXPECT_EQ(csv->body, "time,phi,theta,field,FILE\n0,30,20,T,T/a b.png\n");
  EXPECT_EQ(csv->get_header_value("Referrer-Policy"), "no-referrer");
  EXPECT_EQ(c.Get(r.with_token("/db/T/a%20b.png"))->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(r.server.url(), "http://127.0.0.1:" + std::to_string(r.server.port()) + "/?token=" + r.server.token());
}

TEST(ViewServer, ThePageSetsTheSessionCookie) {
  const Database d;
  Running r(d.db);
  httplib::Client c("127.0.0.1", r.server.port());
  const auto page = c.Get(r.with_token("/"));
  ASSERT_TRUE(page);
  EXPECT_NE(page->body.find("pnb-db-base\" content=\"db/\""), std::string::npos);
  EXPECT_NE(page->body.find("pnb-events\" content=\"true\""), std::string::npos);
  const std::string set_cookie = page->get_header_value("Set-Cookie");
  EXPECT_NE(set_cookie.find("HttpOnly"), std::string::npos);
  EXPECT_NE(set_cookie.find("SameSite=Strict"), std::string::npos);
  const std::string cookie = set_cookie.substr(0, set_cookie.find(';'));
  EXPECT_EQ(c.Get("/db/data.csv", {{"Cookie", cookie}})->status, 200);
  EXPECT_EQ(c.Get("/assets/viewer.js", {{"Cookie", cookie}})->status, 200);
  EXPECT_EQ(c.Get("/assets/missing.js", {{"Cookie", cookie}})->status, 404);
}

TEST(ViewServer, RefusesWhatLeavesTheDatabase) {
  const Database d;
  Running r(d.db);
  httplib::Client c("127.0.0.1", r.server.port());
  for (const std::string path : {"/db/../secret.txt", "/db/%2e%2e/secret.txt", "/db/link-out.txt", "/db/dir-out/x.csv",
                                 "/db/%2fetc%2fpasswd", "/secret.txt", "/db/"}) {
    const auto res = c.Get(r.with_token(path));
    ASSERT_TRUE(res) << path;
    EXPECT_NE(res->status, 200) << path;
    EXPECT_EQ(res->body.find("secret"), std::string::npos) << path;
  }
  EXPECT_EQ(c.Get(r.with_token("/db/" + std::string(4000, 'a')))->status, 414);
  EXPECT_EQ(c.Post(r.with_token("/db/data.csv"), "x", "text/plain")->status, 405);
}

// 50 clients at once for 3 s, mixing the index, an image and refused paths: every answer right,
// no crash (and, in the sanitizer build, no leak); the latencies printed.
TEST(ViewServer, FiftyClientsAtOnce) {
  const Database d;
  Running r(d.db);
  std::atomic<int> wrong{0};
  std::vector<std::vector<double>> latency(50);
  std::vector<std::thread> clients;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  for (int i = 0; i < 50; ++i)
    clients.emplace_back([&, i] {
      httplib::Client c("127.0.0.1", r.server.port());
      for (int k = 0; std::chrono::steady_clock::now() < until; ++k) {
        const char* paths[] = {"/db/data.csv", "/db/T/a%20b.png", "/db/%2e%2e/secret.txt"};
        const int expect[] = {200, 200, 404};
        const auto t0 = std::chrono::steady_clock::now();
        const auto res = c.Get(r.with_token(paths[k % 3]));
        latency[i].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        if (!res || res->status != expect[k % 3]) {
          ++wrong;
          std::fprintf(stderr, "client %d request %d (%.0f ms): %s\n", i, k, latency[i].back(),
                       res ? ("status " + std::to_string(res->status)).c_str() : httplib::to_string(res.error()).c_str());
        }
      }
    });
  for (auto& t : clients) t.join();
  std::vector<double> all;
  for (const auto& l : latency) all.insert(all.end(), l.begin(), l.end());
  std::sort(all.begin(), all.end());
  ASSERT_FALSE(all.empty());
  std::printf("%zu requests from 50 clients in 3 s: median %.2f ms, 99th percentile %.2f ms\n", all.size(),
              all[all.size() / 2], all[all.size() * 99 / 100]);
  EXPECT_EQ(wrong.load(), 0);
}

// A page listening on /events on its own thread: what it received, and the response's headers.
struct Listener {
  std::mutex mutex;
  std::condition_variable changed;
  std::string received;
  int status = 0;
  std::string content_type, content_encoding;
  std::thread thread;

  Listener(int port, const std::string& path) : thread([this, port, path] { listen(port, path); }) {}
  ~Listener() { thread.join(); }
  void listen(int port, const std::string& path) {
    httplib::Client c("127.0.0.1", port);
    c.set_read_timeout(30, 0);
    c.Get(
        path, {{"Accept-Encoding", "gzip, deflate, br"}},
        [this](const httplib::Response& res) {
          std::lock_guard<std::mutex> lock(mutex);
          status = res.status;
          content_type = res.get_header_value("Content-Type");
          content_encoding = res.get_header_value("Content-Encoding");
          changed.notify_all();
          return true;
        },
        [this](const char* data, std::size_t size) {
          std::lock_guard<std::mutex> lock(mutex);
          received.append(data, size);
          changed.notify_all();
          return true;
        });
  }
  bool wait_for(const std::string& text) {
    std::unique_lock<std::mutex> lock(mutex);
    return changed.wait_for(lock, std::chrono::seconds(10), [&] { return received.find(text) != std::string::npos; });
  }
};

bool wait_for_listeners(const ViewServer& server, std::size_t n) {
  for (int i = 0; i < 500 && server.listeners() != n; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return server.listeners() == n;
}

TEST(ViewServer, EventsReachEveryOpenPage) {
  const Database d;
  Running r(d.db);
  r.server.publish_status("no 3D mouse found");
  Listener first(r.server.port(), r.with_token("/events")), second(r.server.port(), r.with_token("/events"));
  ASSERT_TRUE(first.wait_for(status_json("no 3D mouse found"))) << "a new page gets the last status";
  ASSERT_TRUE(second.wait_for(status_json("no 3D mouse found")));
  ViewEvent turn;
  turn.d_phi = -1.5;
  turn.d_time = 0.25;
  r.server.publish(turn);
  r.server.publish_status("3D mouse unplugged; waiting for it to come back");
  for (Listener* page : {&first, &second}) {
    EXPECT_TRUE(page->wait_for("data: " + motion_json(turn) + "\n\n"));
    EXPECT_TRUE(page->wait_for("data: " + status_json("3D mouse unplugged; waiting for it to come back") + "\n\n"));
    std::lock_guard<std::mutex> lock(page->mutex);
    EXPECT_EQ(page->status, 200);
    EXPECT_EQ(page->content_type, "text/event-stream");
    EXPECT_EQ(page->content_encoding, "") << "compressed events would be held back";
  }
  EXPECT_EQ(r.server.listeners(), 2u);
  r.server.stop();
}

TEST(ViewServer, EventsNeedTheToken) {
  const Database d;
  Running r(d.db);
  httplib::Client c("127.0.0.1", r.server.port());
  EXPECT_EQ(c.Get("/events")->status, 403);
  EXPECT_EQ(c.Get("/events?token=" + std::string(32, '0'))->status, 403);
  EXPECT_EQ(r.server.listeners(), 0u);
}

TEST(ViewServer, EventsForABoundedNumberOfPages) {
  const Database d;
  Running r(d.db);
  std::vector<std::unique_ptr<Listener>> pages;
  for (std::size_t i = 0; i < EventHub::kMaxSubscribers; ++i)
    pages.push_back(std::make_unique<Listener>(r.server.port(), r.with_token("/events")));
  ASSERT_TRUE(wait_for_listeners(r.server, EventHub::kMaxSubscribers));
  httplib::Client c("127.0.0.1", r.server.port());
  const auto refused = c.Get(r.with_token("/events"));
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 503);
  // Files are still served while every stream is open.
  EXPECT_EQ(c.Get(r.with_token("/db/data.csv"))->status, 200);
  r.server.stop();
}

TEST(ViewServer, NoEventsWhenTheStreamIsOff) {
  const Database d;
  Running r(d.db, false);
  httplib::Client c("127.0.0.1", r.server.port());
  EXPECT_EQ(c.Get(r.with_token("/events"))->status, 404);
  EXPECT_NE(c.Get(r.with_token("/"))->body.find("pnb-events\" content=\"false\""), std::string::npos);
}

TEST(ViewServer, MissingDatabaseIsAClearError) {
  EXPECT_THROW(ViewServer(ViewOptions{"/nonexistent/db", "127.0.0.1", 0, ""}), Error);
}

TEST(ViewServer, ExportWritesThePageIntoTheDatabase) {
  const Database d;
  export_page(d.db);
  std::ifstream in(d.db / "index.html");
  const std::string html((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(html.find("pnb-db-base\" content=\"\""), std::string::npos);
  EXPECT_NE(html.find("pnb-events\" content=\"false\""), std::string::npos) << "no server to listen to";
  EXPECT_NE(html.find("viewer/viewer.js"), std::string::npos);
  EXPECT_TRUE(fs::exists(d.db / "viewer" / "viewer.js"));
  EXPECT_TRUE(fs::exists(d.db / "viewer" / "viewer.css"));
  EXPECT_THROW(export_page(d.dir / "missing"), Error);
}

}  // namespace
}  // namespace penumbra::viewer
