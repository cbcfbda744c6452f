/// \file option_table.hpp
/// hssbem's options, each declared once in option_table.def: name, type, default, range, the
/// jobs it applies to, the -help section it is listed in, who reads it, and a help line.
///
/// From that one table come
/// - the defaults, as constants the engines' option structs start from
///   (`double rel_tol = option_default::mat_h2_rel_tol;` in H2Options): a default is written
///   once, in the table (ctest -R option_defaults greps the sources for copies);
/// - the rows (option_rows(), find_option()): the PETSc face and the driver read each option by
///   its row and check its value against the row's range (check_option());
/// - `-help` (option_help()), so it cannot drift from what the runs use.
///
/// The values a face gathers (the command line, a Python dict) travel as OptionValues; the
/// session layer turns them into the engines' typed structs (session/options.hpp).
#pragma once

#include <limits>
#include <map>
#include <string>
#include <string_view>

namespace hssbem {

enum class OptionKind { Real, Int, Bool, Text, Choice };

/// The values an option takes: a closed or open interval (infinite ends allowed), plus one
/// extra value outside it (e.g. -1: none), or for a Choice its names ("auto|dense|h2").
struct OptionRange {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  bool has_extra = false;
  double extra = 0;
  std::string_view choices;
};

/// The jobs an option applies to (or'ed).
enum OptionJob : unsigned { kStatic = 1, kScene = 2, kContact = 4, kEvery = 7 };

/// The sections of -help, in the order it lists them.
enum class OptionGroup { Problem, Run, Operator, H2, Hss, Solve, PcH2, PcHss, Scene, Contact, Interior };

/// Who reads an option (option_table.def says what each means).
enum class OptionReader { Driver, System, Pc, Petsc, Face };

/// One option of the table.
struct OptionRow {
  std::string_view name;  ///< the key without its dash
  OptionKind kind;
  double number;          ///< the default of a Real, Int or Bool (0 or 1)
  std::string_view text;  ///< the default of a Text or Choice
  OptionRange range;
  unsigned jobs;          ///< OptionJob bits
  OptionGroup group;
  OptionReader reader;
  std::string_view help;
  std::string_view shown; ///< what -help shows as the default when the value alone would mislead (else empty)
};

template <OptionKind K> struct OptionValueType {
  using type = double;
};
template <> struct OptionValueType<OptionKind::Int> {
  using type = int;
};
template <> struct OptionValueType<OptionKind::Bool> {
  using type = bool;
};
template <> struct OptionValueType<OptionKind::Text> {
  using type = std::string_view;
};
template <> struct OptionValueType<OptionKind::Choice> {
  using type = std::string_view;
};

/// The default of every option, by its name: option_default::mat_h2_rel_tol is 1e-5.
namespace option_default {
#define HSSBEM_OPTION(name, kind, value, range, jobs, group, reader, help, shown) inline constexpr OptionValueType<OptionKind::kind>::type name = value;
#define HSSBEM_DEFAULT(name, value, what) inline constexpr double name = value;
#include "hssbem/core/option_table.def"
#undef HSSBEM_DEFAULT
#undef HSSBEM_OPTION
} // namespace option_default

/// Every row of the table, in its order, and their count.
const OptionRow *option_rows();
int num_option_rows();

/// The row of option `name` (without the dash), or null.
const OptionRow *find_option(std::string_view name);

/// A value given for an option: a number (Real, Int, Bool as 0 or 1) or a text (Text, Choice).
struct OptionValue {
  OptionKind kind = OptionKind::Real;
  double number = 0;
  std::string text;

  static OptionValue of(const OptionRow &row, double number) { return {row.kind, number, ""}; }
  static OptionValue of(const OptionRow &row, std::string text) { return {row.kind, 0, std::move(text)}; }
  /// The default of `row`.
  static OptionValue default_of(const OptionRow &row) { return {row.kind, row.number, std::string(row.text)}; }
};

/// Values by option name (without the dash).
using OptionValues = std::map<std::string, OptionValue>;

/// Why `value` is no value of `row`: "-name must lie in (0, 1), got 2" (a non-finite real, an
/// integer that is not whole, a name that is not a choice); empty when it is one.
std::string option_value_error(const OptionRow &row, const OptionValue &value);

/// Throws std::invalid_argument with option_value_error() unless it is empty.
void check_option(const OptionRow &row, const OptionValue &value);

/// The value as -help and the result file show it: "1e-05", "64", "true", "auto".
std::string option_value_text(const OptionValue &value);

/// The range as -help shows it: "real in (0, 1)", "integer >= 1 or -1", "auto|dense|h2|hss".
std::string option_range_text(const OptionRow &row);

/// "static", "scene, contact", ... for an OptionJob mask.
std::string option_jobs_text(unsigned jobs);

/// -help: the options that apply to `jobs`, section by section (each headed by what it covers
/// and the jobs it serves), one line each: "  -name <default>: help [range]".
std::string option_help(unsigned jobs);

} // namespace hssbem
