// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/main.cpp -- penumbra-view DB [--host H] [--port N] | penumbra-view --export DB
#include <pthread.h>

#include <csignal>
#include <iostream>
#include <string>
#include <thread>

#include "penumbra/core/error.h"
#include "view_server.h"

namespace {

const char* const kUsage =
    "usage: penumbra-view DB [--host ADDRESS] [--port N]\n"
    "       penumbra-view --export DB\n"
    "  Serves the Cinema image database DB to a browser: open the URL it prints (it carries a\n"
    "  per-session token, which keeps other users of the machine out). Listens on 127.0.0.1 and\n"
    "  a free port unless told otherwise. --export writes the page into DB (index.html, viewer/)\n"
    "  so that any static file server shows it.\n";

// SIGINT and SIGTERM are taken by a thread that waits for them (sigwait), so that stopping the
// server happens outside a signal handler.
int serve(const std::string& db, const std::string& host, int port) {
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  penumbra::viewer::ViewServer server({db, host, port, ""});
  std::thread waiter([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    server.stop();
  });
  std::cout << "penumbra-view: serving '" << db << "'; open\n  " << server.url() << "\n" << std::flush;
  server.run();
  // Stopped by a signal, or the server ended by itself: then wake the waiter.
  pthread_kill(waiter.native_handle(), SIGTERM);
  waiter.join();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string db, host = "127.0.0.1";
  int port = 0;
  bool do_export = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--help" || a == "-h") {
        std::cout << kUsage;
        return 0;
      } else if (a == "--export") {
        do_export = true;
      } else if (a == "--host" && i + 1 < argc) {
        host = argv[++i];
      } else if (a == "--port" && i + 1 < argc) {
        port = std::stoi(argv[++i]);
        if (port < 0 || port > 65535) throw std::invalid_argument("port");
      } else if (db.empty() && a.rfind("--", 0) != 0) {
        db = a;
      } else {
        throw std::invalid_argument(a);
      }
    }
    if (db.empty()) throw std::invalid_argument("DB");
  } catch (const std::exception&) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    if (do_export) {
      penumbra::viewer::export_page(db);
      std::cout << "penumbra-view: wrote '" << db << "/index.html'\n";
      return 0;
    }
    return serve(db, host, port);
  } catch (const penumbra::Error& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
}
