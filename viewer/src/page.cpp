// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/page.cpp -- the page's files by name, the page's placeholders, media types
#include <algorithm>

#include "assets.h"

namespace penumbra::viewer {
namespace {

void replace_all(std::string& text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

const Asset* find_asset(const std::string& name) {
  const auto& all = assets();
  const auto it = std::find_if(all.begin(), all.end(), [&](const Asset& a) { return a.name == name; });
  return it == all.end() ? nullptr : &*it;
}

std::string page(const std::string& db_base, const std::string& assets_base, bool live, bool events) {
  std::string html = find_asset("index.html")->content;
  replace_all(html, "{{DB_BASE}}", db_base);
  replace_all(html, "{{ASSETS}}", assets_base);
  replace_all(html, "{{LIVE}}", live ? "true" : "false");
  replace_all(html, "{{EVENTS}}", events ? "true" : "false");
  return html;
}

std::string media_type(const std::string& path) {
  static const std::pair<const char*, const char*> types[] = {
      {".png", "image/png"},   {".csv", "text/csv; charset=utf-8"},  {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"}, {".json", "application/json"},
      {".jpg", "image/jpeg"}, {".jpeg", "image/jpeg"}};
  for (const auto& [extension, type] : types)
    if (ends_with(path, extension)) return type;
  return "application/octet-stream";
}

}  // namespace penumbra::viewer
