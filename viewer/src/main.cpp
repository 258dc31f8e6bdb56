// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/main.cpp -- penumbra-view DB [--store DIR [--config FILE]] [--host H] [--port N] | --export DB
#include <pthread.h>

#include <csignal>
#include <iostream>
#include <string>
#include <thread>

#include "penumbra/core/error.h"
#include "view_server.h"

namespace {

const char* const kUsage =
    "usage: penumbra-view DB [--store DIR [--config FILE]] [--host ADDRESS] [--port N]\n"
    "       penumbra-view --export DB\n"
    "  Serves the Cinema image database DB to a browser: open the URL it prints (it carries a\n"
    "  per-session token, which keeps other users of the machine out). Listens on 127.0.0.1 and\n"
    "  a free port unless told otherwise. --export writes the page into DB (index.html, viewer/)\n"
    "  so that any static file server shows it. With --store (the run's \"store\" directory, which\n"
    "  keeps the run's config; --config names another), the page also renders views that were\n"
    "  never stored: any camera, transfer function and stored step.\n";

// SIGINT and SIGTERM are taken by a thread that waits for them (sigwait), so that stopping the
// server happens outside a signal handler.
int serve(const penumbra::viewer::ViewOptions& options) {
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  penumbra::viewer::ViewServer server(options);
  std::thread waiter([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    server.stop();
  });
  std::cout << "penumbra-view: serving '" << options.database.string() << "'"
            << (options.store.empty() ? "" : " and views of the store '" + options.store + "'") << "; open\n  "
            << server.url() << "\n"
            << std::flush;
  server.run();
  // Stopped by a signal, or the server ended by itself: then wake the waiter.
  pthread_kill(waiter.native_handle(), SIGTERM);
  waiter.join();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  penumbra::viewer::ViewOptions options;
  std::string db;
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
        options.host = argv[++i];
      } else if (a == "--port" && i + 1 < argc) {
        options.port = std::stoi(argv[++i]);
        if (options.port < 0 || options.port > 65535) throw std::invalid_argument("port");
      } else if (a == "--store" && i + 1 < argc) {
        options.store = argv[++i];
      } else if (a == "--config" && i + 1 < argc) {
        options.config = argv[++i];
      } else if (db.empty() && a.rfind("--", 0) != 0) {
        db = a;
      } else {
        throw std::invalid_argument(a);
      }
    }
    if (db.empty()) throw std::invalid_argument("DB");
    if (options.store.empty() && !options.config.empty()) throw std::invalid_argument("--config needs --store");
    options.database = db;
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
    return serve(options);
  } catch (const penumbra::Error& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
}
