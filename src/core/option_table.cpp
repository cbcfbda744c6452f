// The table of options (see option_table.hpp): its rows, their checks and -help.
#include "hssbem/core/option_table.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace hssbem {

namespace {

// The syntax of option_table.def's rows, only while the rows are made.
namespace syntax {

constexpr OptionRange any() { return {}; }
constexpr OptionRange interval(double lo, double hi, bool lo_open, bool hi_open)
{
  OptionRange r;
  r.lo = lo, r.hi = hi, r.lo_open = lo_open, r.hi_open = hi_open;
  return r;
}
constexpr OptionRange in_open(double lo, double hi) { return interval(lo, hi, true, true); }
constexpr OptionRange in_closed(double lo, double hi) { return interval(lo, hi, false, false); }
constexpr OptionRange in_open_closed(double lo, double hi) { return interval(lo, hi, true, false); }
constexpr OptionRange in_closed_open(double lo, double hi) { return interval(lo, hi, false, true); }
constexpr OptionRange above(double lo) { return interval(lo, std::numeric_limits<double>::infinity(), true, false); }
constexpr OptionRange at_least(double lo) { return interval(lo, std::numeric_limits<double>::infinity(), false, false); }
constexpr OptionRange or_value(OptionRange r, double v)
{
  r.has_extra = true, r.extra = v;
  return r;
}
constexpr OptionRange choices(std::string_view names)
{
  OptionRange r;
  r.choices = names;
  return r;
}

constexpr OptionGroup kGroupProblem = OptionGroup::Problem, kGroupRun = OptionGroup::Run, kGroupOperator = OptionGroup::Operator, kGroupH2 = OptionGroup::H2,
                      kGroupHss = OptionGroup::Hss, kGroupSolve = OptionGroup::Solve, kGroupPcH2 = OptionGroup::PcH2, kGroupPcHss = OptionGroup::PcHss,
                      kGroupScene = OptionGroup::Scene, kGroupContact = OptionGroup::Contact, kGroupInterior = OptionGroup::Interior;
constexpr OptionReader kDriver = OptionReader::Driver, kSystem = OptionReader::System, kPc = OptionReader::Pc, kPetsc = OptionReader::Petsc, kFace = OptionReader::Face;

constexpr double number_of(double v) { return v; }
constexpr double number_of(int v) { return v; }
constexpr double number_of(bool v) { return v ? 1 : 0; }
constexpr double number_of(std::string_view) { return 0; }
constexpr std::string_view text_of(std::string_view v) { return v; }
template <class T> constexpr std::string_view text_of(T) { return {}; }

constexpr OptionRow k_rows[] = {
#define HSSBEM_OPTION(name, kind, value, range, jobs, group, reader, help, shown) \
  {#name, OptionKind::kind, number_of(option_default::name), text_of(option_default::name), range, jobs, group, reader, help, shown},
#define HSSBEM_DEFAULT(name, value, what)
#include "hssbem/core/option_table.def"
#undef HSSBEM_DEFAULT
#undef HSSBEM_OPTION
};

} // namespace syntax

constexpr int k_num_rows = static_cast<int>(sizeof(syntax::k_rows) / sizeof(syntax::k_rows[0]));

/// "1e-05", "2", "-1", "1e+18", "inf": the shortest round-trip form of the number.
std::string number_text(double v)
{
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

bool in_interval(const OptionRange &r, double v)
{
  const bool lo_ok = r.lo_open ? v > r.lo : v >= r.lo, hi_ok = r.hi_open ? v < r.hi : v <= r.hi;
  return lo_ok && hi_ok;
}

std::string interval_text(const OptionRange &r)
{
  const bool lo_inf = std::isinf(r.lo), hi_inf = std::isinf(r.hi);
  if (lo_inf && hi_inf) return "";
  if (hi_inf) return std::string(r.lo_open ? "> " : ">= ") + number_text(r.lo);
  if (lo_inf) return std::string(r.hi_open ? "< " : "<= ") + number_text(r.hi);
  return std::string("in ") + (r.lo_open ? "(" : "[") + number_text(r.lo) + ", " + number_text(r.hi) + (r.hi_open ? ")" : "]");
}

bool is_choice(const OptionRange &r, std::string_view v)
{
  std::string_view rest = r.choices;
  while (true) {
    const std::size_t bar = rest.find('|');
    if (rest.substr(0, bar) == v) return true;
    if (bar == std::string_view::npos) return false;
    rest = rest.substr(bar + 1);
  }
}

const char *group_title(OptionGroup g)
{
  switch (g) {
  case OptionGroup::Problem: return "The problem (command-line values win over the problem file)";
  case OptionGroup::Run: return "The run";
  case OptionGroup::Operator: return "The BEM operator";
  case OptionGroup::H2: return "The H2 compression (the H2 operator; contact's H2 reference factorizations)";
  case OptionGroup::Hss: return "The HSS compression (the HSS operator)";
  case OptionGroup::Solve: return "The main solve (PETSc's options, no prefix; hssbem's defaults)";
  case OptionGroup::PcH2: return "PC h2: the H2 factorization (-pc_type h2)";
  case OptionGroup::PcHss: return "PC hss: the ULV factorization of an HSS compression (-pc_type hss)";
  case OptionGroup::Scene: return "Scenes (problem files with \"frames\")";
  case OptionGroup::Contact: return "Contact (problem files with \"contact\")";
  case OptionGroup::Interior: return "Displacement and stress inside the body (interior points and grids)";
  }
  return "";
}

/// The jobs the rows of group g apply to, together.
unsigned group_jobs(OptionGroup g)
{
  unsigned jobs = 0;
  for (int i = 0; i < k_num_rows; ++i)
    if (syntax::k_rows[i].group == g) jobs |= syntax::k_rows[i].jobs;
  return jobs;
}

std::string help_line(const OptionRow &row)
{
  const std::string value = row.shown.empty() ? option_value_text(OptionValue::default_of(row)) : std::string(row.shown);
  const std::string range = option_range_text(row);
  return "  -" + std::string(row.name) + " <" + value + ">: " + std::string(row.help) + (range.empty() ? "" : " [" + range + "]") + "\n";
}

} // namespace

const OptionRow *option_rows() { return syntax::k_rows; }

int num_option_rows() { return k_num_rows; }

const OptionRow *find_option(std::string_view name)
{
  for (const OptionRow &r : syntax::k_rows)
    if (r.name == name) return &r;
  return nullptr;
}

std::string option_value_error(const OptionRow &row, const OptionValue &value)
{
  const std::string key = "-" + std::string(row.name);
  switch (row.kind) {
  case OptionKind::Text: return "";
  case OptionKind::Choice:
    if (is_choice(row.range, value.text)) return "";
    return key + " " + value.text + " is not available; use " + std::string(row.range.choices);
  case OptionKind::Bool: return value.number == 0 || value.number == 1 ? "" : key + " must be true or false";
  case OptionKind::Int:
  case OptionKind::Real: break;
  }
  const double v = value.number;
  const bool whole = row.kind != OptionKind::Int || (std::isfinite(v) && v == std::floor(v));
  if (std::isfinite(v) && whole && (in_interval(row.range, v) || (row.range.has_extra && v == row.range.extra))) return "";
  const std::string range = interval_text(row.range), extra = row.range.has_extra ? number_text(row.range.extra) : "";
  std::string must = range.empty() ? "must be finite" : range.rfind("in ", 0) == 0 ? "must lie " + range : "must be " + range;
  if (!extra.empty()) must += " (or " + extra + ")";
  return key + " " + must + ", got " + number_text(v);
}

void check_option(const OptionRow &row, const OptionValue &value)
{
  const std::string why = option_value_error(row, value);
  if (!why.empty()) throw std::invalid_argument(why);
}

std::string option_value_text(const OptionValue &value)
{
  switch (value.kind) {
  case OptionKind::Bool: return value.number != 0 ? "true" : "false";
  case OptionKind::Text:
  case OptionKind::Choice: return value.text;
  case OptionKind::Int:
  case OptionKind::Real: break;
  }
  return number_text(value.number);
}

std::string option_range_text(const OptionRow &row)
{
  switch (row.kind) {
  case OptionKind::Bool: return "true|false";
  case OptionKind::Text: return "";
  case OptionKind::Choice: return std::string(row.range.choices);
  case OptionKind::Int:
  case OptionKind::Real: break;
  }
  std::string text = row.kind == OptionKind::Int ? "integer" : "real";
  const std::string interval = interval_text(row.range);
  if (!interval.empty()) text += " " + interval;
  if (row.range.has_extra) text += " or " + number_text(row.range.extra);
  return text;
}

std::string option_jobs_text(unsigned jobs)
{
  std::string out;
  const std::pair<unsigned, const char *> names[] = {{kStatic, "static"}, {kScene, "scene"}, {kContact, "contact"}};
  for (const auto &[bit, name] : names)
    if (jobs & bit) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

std::string option_help(unsigned jobs)
{
  std::string out;
  for (int g = static_cast<int>(OptionGroup::Problem); g <= static_cast<int>(OptionGroup::Interior); ++g) {
    const OptionGroup group = static_cast<OptionGroup>(g);
    std::string lines;
    for (const OptionRow &r : syntax::k_rows)
      if (r.group == group && (r.jobs & jobs)) lines += help_line(r);
    if (lines.empty()) continue;
    const unsigned serves = group_jobs(group);
    out += std::string(group_title(group)) + " [" + (serves == kEvery ? std::string("every job") : option_jobs_text(serves)) + "]:\n" + lines;
  }
  return out;
}

} // namespace hssbem
