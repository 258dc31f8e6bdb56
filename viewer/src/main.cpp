// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/main.cpp -- penumbra-view DB [--store DIR [--config FILE]] [--host H] [--port N]
// [--spacemouse ...] | --export DB
#include <pthread.h>

#include <csignal>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include "penumbra/core/error.h"
#include "scripted_transport.h"
#include "spacemouse_device.h"
#include "view_server.h"

namespace {

using namespace penumbra::viewer;

const char* const kUsage =
    "usage: penumbra-view DB [--store DIR [--config FILE]] [--host ADDRESS] [--port N]\n"
    "                        [--spacemouse on|off] [--spacemouse-sensitivity X] [--spacemouse-deadzone N]\n"
    "       penumbra-view --export DB\n"
    "  Serves the Cinema image database DB to a browser: open the URL it prints (it carries a\n"
    "  per-session token, which keeps other users of the machine out). Listens on 127.0.0.1 and\n"
    "  a free port unless told otherwise. --export writes the page into DB (index.html, viewer/)\n"
    "  so that any static file server shows it. With --store (the run's \"store\" directory, which\n"
    "  keeps the run's config; --config names another), the page also renders views that were\n"
    "  never stored: any camera, transfer function and stored step.\n"
    "  A 3D mouse (3Dconnexion, over USB) orbits, zooms and moves time in every open page unless\n"
    "  --spacemouse off; sensitivity (0, 10], default 1; dead zone in device units [0, 350),\n"
    "  default 15. viewer/README.md has the udev rule it needs.\n";

struct Options {
  ViewOptions view;
  bool do_export = false;
  bool spacemouse = true;
  MappingSettings mapping;
  std::string script;  ///< --spacemouse-script: recorded reports instead of USB (the browser test)
};

bool on_off(const std::string& value) {
  if (value != "on" && value != "off") throw std::invalid_argument("--spacemouse " + value);
  return value == "on";
}

Options parse(int argc, char** argv) {
  Options o;
  std::string db;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--export") {
      o.do_export = true;
    } else if (a == "--host" && has_value) {
      o.view.host = argv[++i];
    } else if (a == "--port" && has_value) {
      o.view.port = std::stoi(argv[++i]);
      if (o.view.port < 0 || o.view.port > 65535) throw std::invalid_argument("port");
    } else if (a == "--store" && has_value) {
      o.view.store = argv[++i];
    } else if (a == "--config" && has_value) {
      o.view.config = argv[++i];
    } else if (a == "--spacemouse" && has_value) {
      o.spacemouse = on_off(argv[++i]);
    } else if (a == "--spacemouse-sensitivity" && has_value) {
      o.mapping.sensitivity = std::stod(argv[++i]);
    } else if (a == "--spacemouse-deadzone" && has_value) {
      o.mapping.dead_zone = std::stoi(argv[++i]);
    } else if (a == "--spacemouse-script" && has_value) {
      o.script = argv[++i];
    } else if (db.empty() && a.rfind("--", 0) != 0) {
      db = a;
    } else {
      throw std::invalid_argument(a);
    }
  }
  if (db.empty()) throw std::invalid_argument("DB");
  if (o.view.store.empty() && !o.view.config.empty()) throw std::invalid_argument("--config needs --store");
  o.view.database = db;
  return o;
}

void say(const std::string& line) { std::cout << "penumbra-view: " << line << "\n" << std::flush; }

// The 3D mouse's device: the script's, the system's USB, or none (off, or built without libusb).
std::unique_ptr<SpaceMouseTransport> spacemouse_transport(const Options& o, ScriptedTransport*& scripted) {
  if (!o.spacemouse) return nullptr;
  if (!o.script.empty()) {
    auto transport = std::make_unique<ScriptedTransport>(read_report_script_file(o.script), "scripted 3D mouse");
    scripted = transport.get();
    return transport;
  }
  auto usb = system_spacemouse_transport();
  if (!usb) say("built without libusb-1.0: no 3D mouse");
  return usb;
}

// SIGINT and SIGTERM are taken by a thread that waits for them (sigwait), so that stopping the
// server happens outside a signal handler. With a report script, SIGUSR1 plugs its device in.
int serve(Options o) {
  ScriptedTransport* scripted = nullptr;
  auto transport = spacemouse_transport(o, scripted);
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  if (scripted) sigaddset(&signals, SIGUSR1);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  o.view.event_stream = transport != nullptr;
  ViewServer server(o.view);
  std::unique_ptr<SpaceMouse> mouse;
  if (transport)
    mouse = std::make_unique<SpaceMouse>(
        std::move(transport), SpaceMouseOptions{o.mapping}, [&server](const ViewEvent& e) { server.publish(e); },
        [&server](const std::string& status) {
          say(status);
          server.publish_status(status);
        });
  std::thread waiter([&] {
    int signal = 0;
    while (sigwait(&signals, &signal) == 0 && signal == SIGUSR1) scripted->plug_in();
    server.stop();
  });
  say("serving '" + o.view.database.string() + "'" +
      (o.view.store.empty() ? "" : " and views of the store '" + o.view.store + "'") + "; open\n  " + server.url());
  if (mouse) mouse->start();
  server.run();
  if (mouse) mouse->stop();
  // Stopped by a signal, or the server ended by itself: then wake the waiter.
  pthread_kill(waiter.native_handle(), SIGTERM);
  waiter.join();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::cout << kUsage;
      return 0;
    }
  Options options;
  try {
    options = parse(argc, argv);
  } catch (const std::exception&) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    check_settings(options.mapping);
    if (options.do_export) {
      export_page(options.view.database);
      say("wrote '" + options.view.database.string() + "/index.html'");
      return 0;
    }
    return serve(std::move(options));
  } catch (const penumbra::Error& e) {
    std::cerr << e.what() << "\n";
    return e.code() == penumbra::ErrorCode::invalid_argument ? 2 : 1;
  }
}
