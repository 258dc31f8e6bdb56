// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/trigger_expression.cpp -- a small recursive-descent parser and its evaluation
#include "trigger_expression.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "penumbra/core/error.h"

namespace penumbra::insitu {

struct TriggerExpression::Node {
  enum class Kind { any, all, compare } kind = Kind::compare;
  std::vector<std::shared_ptr<const Node>> children;  // any / all
  // compare: STAT(field) or change(STAT(field)), OP, number
  std::string stat, field, op;
  bool change = false;
  double number = 0;
};

namespace {

using Node = TriggerExpression::Node;

class Parser {
public:
  Parser(const std::string& text, const std::string& path) : m_text(text), m_path(path) {}

  std::shared_ptr<const Node> expression() {
    auto root = any();
    skip_space();
    if (m_at < m_text.size()) fail("unexpected '" + m_text.substr(m_at, 12) + "'");
    return root;
  }
  std::vector<std::string> fields;

private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ErrorCode::invalid_argument, "config: " + m_path + ": " + what + " at character " + std::to_string(m_at + 1) +
                                                 " of \"" + m_text + "\" (expected e.g. \"max(T) > 500\" or "
                                                 "\"change(mean(p)) > 5%\", joined by and / or)");
  }
  void skip_space() {
    while (m_at < m_text.size() && std::isspace(static_cast<unsigned char>(m_text[m_at]))) ++m_at;
  }
  bool accept(const std::string& token) {
    skip_space();
    if (m_text.compare(m_at, token.size(), token) != 0) return false;
    const std::size_t end = m_at + token.size();
    // A word ends where a name could not go on.
    if (std::isalpha(static_cast<unsigned char>(token.back())) && end < m_text.size() &&
        (std::isalnum(static_cast<unsigned char>(m_text[end])) || m_text[end] == '_'))
      return false;
    m_at = end;
    return true;
  }
  void expect(const std::string& token) {
    if (!accept(token)) fail("expected '" + token + "'");
  }
  // `or` joins `and` groups, which join comparisons: and binds first.
  std::shared_ptr<const Node> any() { return joined(Node::Kind::any, "or", &Parser::all); }
  std::shared_ptr<const Node> all() { return joined(Node::Kind::all, "and", &Parser::compare); }
  std::shared_ptr<const Node> joined(Node::Kind kind, const char* word, std::shared_ptr<const Node> (Parser::*part)()) {
    auto first = (this->*part)();
    if (!accept(word)) return first;
    auto n = std::make_shared<Node>();
    n->kind = kind;
    n->children.push_back(first);
    do n->children.push_back((this->*part)());
    while (accept(word));
    return n;
  }
  std::shared_ptr<const Node> compare() {
    auto n = std::make_shared<Node>();
    n->change = accept("change");
    if (n->change) expect("(");
    statistic(*n);
    if (n->change) expect(")");
    for (const char* op : {">=", "<=", ">", "<"})
      if (accept(op)) {
        n->op = op;
        break;
      }
    if (n->op.empty()) fail("expected a comparison (> >= < <=)");
    n->number = number();
    return n;
  }
  void statistic(Node& n) {
    for (const char* stat : {"min", "max", "mean"})
      if (accept(stat)) n.stat = stat;
    if (n.stat.empty()) fail("expected min(FIELD), max(FIELD), mean(FIELD) or change(...)");
    expect("(");
    skip_space();
    const std::size_t start = m_at;
    while (m_at < m_text.size() && m_text[m_at] != ')' && !std::isspace(static_cast<unsigned char>(m_text[m_at]))) ++m_at;
    n.field = m_text.substr(start, m_at - start);
    if (n.field.empty()) fail("expected a field name");
    expect(")");
    if (std::find(fields.begin(), fields.end(), n.field) == fields.end()) fields.push_back(n.field);
  }
  double number() {
    skip_space();
    const char* begin = m_text.c_str() + m_at;
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (end == begin || !std::isfinite(v)) fail("expected a finite number");
    m_at += static_cast<std::size_t>(end - begin);
    return accept("%") ? v / 100 : v;
  }

  const std::string& m_text;
  const std::string& m_path;
  std::size_t m_at = 0;
};

double statistic(const FieldStats& s, const std::string& stat) {
  return stat == "min" ? s.min : stat == "max" ? s.max : s.mean;
}

bool holds_node(const Node& n, const StatsByField& now, const StatsByField* then) {
  if (n.kind == Node::Kind::any)
    return std::any_of(n.children.begin(), n.children.end(), [&](const auto& c) { return holds_node(*c, now, then); });
  if (n.kind == Node::Kind::all)
    return std::all_of(n.children.begin(), n.children.end(), [&](const auto& c) { return holds_node(*c, now, then); });
  const auto it = now.find(n.field);
  if (it == now.end()) return false;
  double v = statistic(it->second, n.stat);
  if (n.change) {
    const auto past = then ? then->find(n.field) : now.end();
    if (!then || past == then->end()) {
      v = std::numeric_limits<double>::infinity();
    } else {
      const double before = statistic(past->second, n.stat);
      v = std::fabs(v - before) / std::max(std::fabs(before), std::numeric_limits<double>::min());
    }
  }
  if (n.op == ">") return v > n.number;
  if (n.op == ">=") return v >= n.number;
  if (n.op == "<") return v < n.number;
  return v <= n.number;
}

}  // namespace

TriggerExpression::TriggerExpression(const std::string& text, const std::string& path) : m_text(text) {
  Parser p(m_text, path);
  m_root = p.expression();
  m_fields = std::move(p.fields);
}

TriggerExpression::~TriggerExpression() = default;
TriggerExpression::TriggerExpression(const TriggerExpression&) = default;
TriggerExpression& TriggerExpression::operator=(const TriggerExpression&) = default;

bool TriggerExpression::holds(const StatsByField& now, const StatsByField* at_last_fire) const {
  return holds_node(*m_root, now, at_last_fire);
}

}  // namespace penumbra::insitu
