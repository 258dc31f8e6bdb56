// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/trigger_expression.h -- "trigger": {"when": ...}: render when the fields' statistics
// say so
#pragma once
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace penumbra::insitu {

/// A field's statistics over one step's finite point values.
struct FieldStats {
  double min = 0, max = 0, mean = 0;
};
using StatsByField = std::map<std::string, FieldStats>;

/// A condition on the fields' statistics, such as
///   max(temperature) > 500
///   change(mean(p)) > 5% or min(rho) <= 0.1
/// Grammar: comparisons `VALUE OP NUMBER[%]` joined by `and` (binding first) and `or`; VALUE is
/// `min(F)`, `max(F)`, `mean(F)` or `change(STAT(F))`, the relative change of a statistic since
/// the step that last fired by this rule (|now - then| / |then|; infinite before any), OP one of
/// > >= < <=, and NUMBER% a hundredth of NUMBER. Field names are the published ones.
class TriggerExpression {
public:
  /// Throws Error(invalid_argument) "config: PATH: ..." naming what is wrong and where.
  TriggerExpression(const std::string& text, const std::string& path);
  ~TriggerExpression();
  TriggerExpression(const TriggerExpression&);
  TriggerExpression& operator=(const TriggerExpression&);

  const std::string& text() const { return m_text; }
  /// The fields it reads, each once.
  const std::vector<std::string>& fields() const { return m_fields; }
  /// Whether it holds for statistics `now`, against `at_last_fire` (null before it first fired).
  /// A field missing from `now` makes its comparisons false.
  bool holds(const StatsByField& now, const StatsByField* at_last_fire) const;

  struct Node;

private:
  std::string m_text;
  std::vector<std::string> m_fields;
  std::shared_ptr<const Node> m_root;
};

}  // namespace penumbra::insitu
