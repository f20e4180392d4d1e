#pragma once
// The command line of every program (CLI11): `pbnbv` and its commands, each service, the twin.
// Options come from the settings table (core/base/setting.hpp: name, default, range, unit, help),
// so a default, its range and its help text are written once. Every program:
//   - answers -h/--help (per command) and --version (the project's version) and exits 0;
//   - rejects, naming the option, a missing value ("--out --views 3", or "--views" last), an
//     option given twice, a number that is not one or lies outside its range (with the value and
//     the range), a choice that is not one of its names (with the names), an unknown option
//     (suggesting the closest one) and a stray word; and exits 2.
// A command with add_settings_file() also reads its options from a TOML file (`name = value`
// lines, the option names without "--"); options on the command line override the file.
#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "core/base/enum_names.hpp"
#include "core/base/setting.hpp"

namespace pbnbv::cli {

// Sets up a program's app (pbnbv, a service, the twin): --version, help layout, unknown options
// reported by parse() rather than by CLI11. `name` is the program's name.
void init(CLI::App& app);

// A command of `pbnbv` (scan, bench, ...), set up as init() does.
CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& description);

// Parses argv. Returns std::nullopt when the program should go on, or the exit code when it
// should stop: 0 after printing the help or the version to `out`, 2 after printing what is wrong
// with the command line to `err` (prefixed with the program and command names). Applies the
// settings files of the commands given (add_settings_file).
std::optional<int> parse(CLI::App& app, int argc, const char* const* argv, std::ostream& out, std::ostream& err);

// --config FILE on `command`: its options' values from a TOML file (see the top of this file).
CLI::Option* add_settings_file(CLI::App& command);

// Applies a settings file to `command`: every option named in the file and not given on the
// command line takes the file's value, checked as if given on the command line. Throws
// std::invalid_argument naming the file and the setting (unknown name, section, bad value).
void apply_settings_file(CLI::App& command, const std::string& path);

namespace detail {
// "" when `text` is a usable value for an option; else why not. A text that looks like an option
// ("--views") means the value is missing: CLI11 would take the next option as the value.
std::string missing_value(const std::string& text);
// Whole numbers and finite reals, the whole text: false otherwise.
bool parse_number(const std::string& text, long long* v);
bool parse_number(const std::string& text, double* v);
std::string type_name(std::string_view unit, bool integral);
// "x,y,z" -> three finite numbers; std::nullopt otherwise.
std::optional<Eigen::Vector3d> parse_point(const std::string& text);
// "a,b,...": exactly `count` finite numbers, the whole text; std::nullopt otherwise.
std::optional<std::vector<double>> parse_numbers(const std::string& text, std::size_t count);
// "a,b,,c" -> {"a", "b", "c"} (empty parts dropped).
std::vector<std::string> split_list(const std::string& text, char separator = ',');
CLI::Option* finish(CLI::Option* o, const std::string& type);

// What a settings file may give an option (TOML's own types): a number, a string (a name, a
// path, a choice), a list (an array of strings, or one string "a,b"), a point (an array of three
// numbers, or one string "x,y,z"), true or false.
enum class ValueKind { kNumber, kText, kList, kPoint, kBool };
// Marks `o` as taking `kind` (a validator that passes everything, named for the kind).
CLI::Option* takes(CLI::Option* o, ValueKind kind);

// "" when `text` is a number of T inside the setting's range; else why not.
template <typename T>
std::string check_number(const Setting<T>& s, const std::string& text) {
  const std::string missing = missing_value(text);
  if (!missing.empty()) return missing;
  if constexpr (std::is_integral_v<T>) {
    long long v = 0;
    if (!parse_number(text, &v)) return "'" + text + "' is not a whole number";
    if (v < static_cast<long long>(s.min) || v > static_cast<long long>(s.max)) {
      return text + " is outside its range " + s.range_text();
    }
  } else {
    double v = 0;
    if (!parse_number(text, &v)) return "'" + text + "' is not a number";
    if (!s.allows(static_cast<T>(v))) return text + " is outside its range " + s.range_text();
  }
  return "";
}

// The number in `text` (already checked by check_number).
template <typename T>
T to_number(const std::string& text) {
  if constexpr (std::is_integral_v<T>) {
    long long v = 0;
    parse_number(text, &v);
    return static_cast<T>(v);
  } else {
    double v = 0;
    parse_number(text, &v);
    return static_cast<T>(v);
  }
}

// "<help> [<default> <unit>] (range [min, max] <unit>)".
template <typename T>
std::string described(const Setting<T>& s, const std::string& default_text, bool with_unit) {
  const bool unit = with_unit && !s.unit.empty();
  return fmt::format("{} [{}{}{}] (range {})", s.help, default_text, unit ? " " : "", unit ? s.unit : "",
                     s.range_text());
}

// "red|green|blue": the names of E, as the help's type.
template <typename E>
std::string type_of_choice() {
  std::string t;
  for (const auto& n : names_of<E>()) t += (t.empty() ? "" : "|") + n;
  return t;
}

// "" when `text` is one of E's names; else why not (naming the choices).
template <typename E>
std::string check_choice(const std::string& text) {
  const std::string missing = missing_value(text);
  if (!missing.empty()) return missing;
  try {
    parse_name<E>(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
}  // namespace detail

// --<name> N: a number from the table, checked against its range, into *target (which keeps the
// default, s.value, unless given).
template <typename T>
CLI::Option* add(CLI::App& app, const Setting<T>& s, T* target) {
  *target = s.value;
  auto* o = app.add_option_function<std::string>(
      "--" + std::string(s.name), [target](const std::string& text) { *target = detail::to_number<T>(text); },
      detail::described(s, fmt::format("{}", s.value), true));
  o->check(CLI::Validator([s](std::string& text) { return detail::check_number(s, text); }, ""));
  detail::takes(o, detail::ValueKind::kNumber);
  return detail::finish(o, detail::type_name(s.unit, std::is_integral_v<T>));
}

// The same for a number whose default depends on other options (e.g. --cx: width / 2):
// *target stays empty unless given; `default_text` says what the default is.
template <typename T>
CLI::Option* add(CLI::App& app, const Setting<T>& s, std::optional<T>* target, const std::string& default_text) {
  target->reset();
  auto* o = app.add_option_function<std::string>(
      "--" + std::string(s.name), [target](const std::string& text) { *target = detail::to_number<T>(text); },
      detail::described(s, default_text, false));
  o->check(CLI::Validator([s](std::string& text) { return detail::check_number(s, text); }, ""));
  detail::takes(o, detail::ValueKind::kNumber);
  return detail::finish(o, detail::type_name(s.unit, std::is_integral_v<T>));
}

// --<name> a|b|c: one of an enum's names (EnumNames<E>) into *target.
template <typename E>
CLI::Option* add(CLI::App& app, const ChoiceSetting<E>& s, E* target) {
  *target = s.value;
  auto* o = app.add_option_function<std::string>(
      "--" + std::string(s.name), [target](const std::string& text) { *target = parse_name<E>(text); },
      fmt::format("{} [{}]", s.help, name_of(s.value)));
  o->check(CLI::Validator([](std::string& text) { return detail::check_choice<E>(text); }, ""));
  detail::takes(o, detail::ValueKind::kText);
  return detail::finish(o, detail::type_of_choice<E>());
}

// The same for a choice whose default depends on other options (e.g. --up: the object's own).
template <typename E>
CLI::Option* add(CLI::App& app, const ChoiceSetting<E>& s, std::optional<E>* target) {
  target->reset();
  auto* o = app.add_option_function<std::string>(
      "--" + std::string(s.name), [target](const std::string& text) { *target = parse_name<E>(text); },
      std::string(s.help));
  o->check(CLI::Validator([](std::string& text) { return detail::check_choice<E>(text); }, ""));
  detail::takes(o, detail::ValueKind::kText);
  return detail::finish(o, detail::type_of_choice<E>());
}

// --<name> a,b,...: a list of an enum's names, none twice, at least one, into *target (which
// keeps its value unless given).
template <typename E>
CLI::Option* add_list(CLI::App& app, const std::string& name, std::vector<E>* target, const std::string& help) {
  std::string defaults;
  for (const E e : *target) defaults += (defaults.empty() ? "" : ",") + std::string(name_of(e));
  auto* o = app.add_option_function<std::string>(
      "--" + name,
      [target](const std::string& text) {
        target->clear();
        for (const auto& part : detail::split_list(text)) target->push_back(parse_name<E>(part));
      },
      fmt::format("{} [{}]", help, defaults));
  o->check(CLI::Validator(
      [](std::string& text) -> std::string {
        const std::string missing = detail::missing_value(text);
        if (!missing.empty()) return missing;
        const std::vector<std::string> parts = detail::split_list(text);
        if (parts.empty()) return "'" + text + "' names no " + std::string(EnumNames<E>::what);
        for (std::size_t i = 0; i < parts.size(); ++i) {
          const std::string bad = detail::check_choice<E>(parts[i]);
          if (!bad.empty()) return bad;
          for (std::size_t k = 0; k < i; ++k) {
            if (parts[k] == parts[i]) return "'" + parts[i] + "' is listed twice";
          }
        }
        return "";
      },
      ""));
  detail::takes(o, detail::ValueKind::kList);
  return detail::finish(o, detail::type_of_choice<E>() + ",...");
}

// --<name> N[,N...]: one or more numbers from the table, each checked against its range, none
// twice, into *target (which is {s.value} unless given); `help` is added to the setting's.
template <typename T>
CLI::Option* add_values(CLI::App& app, const Setting<T>& s, std::vector<T>* target, const std::string& help) {
  *target = {s.value};
  auto* o = app.add_option_function<std::string>(
      "--" + std::string(s.name),
      [target](const std::string& text) {
        target->clear();
        for (const auto& part : detail::split_list(text)) target->push_back(detail::to_number<T>(part));
      },
      detail::described(s, fmt::format("{}", s.value), true) + "; " + help);
  o->check(CLI::Validator(
      [s](std::string& text) -> std::string {
        const std::string missing = detail::missing_value(text);
        if (!missing.empty()) return missing;
        const std::vector<std::string> parts = detail::split_list(text);
        if (parts.empty()) return "'" + text + "' lists no value";
        for (std::size_t i = 0; i < parts.size(); ++i) {
          const std::string bad = detail::check_number(s, parts[i]);
          if (!bad.empty()) return bad;
          for (std::size_t k = 0; k < i; ++k) {
            if (detail::to_number<T>(parts[k]) == detail::to_number<T>(parts[i])) return "'" + parts[i] + "' is listed twice";
          }
        }
        return "";
      },
      ""));
  detail::takes(o, detail::ValueKind::kList);
  return detail::finish(o, detail::type_name(s.unit, std::is_integral_v<T>) + "[,...]");
}

// --<name> a[,b...]: one or more of a choice's names, none twice, into *target (which is
// {s.value} unless given); `help` is added to the setting's.
template <typename E>
CLI::Option* add_list(CLI::App& app, const ChoiceSetting<E>& s, std::vector<E>* target, const std::string& help) {
  *target = {s.value};
  return add_list(app, std::string(s.name), target, std::string(s.help) + "; " + help);
}

// --<name> TEXT into *target (which keeps its value unless given).
CLI::Option* add_text(CLI::App& app, const std::string& name, std::string* target, const std::string& help,
                      const std::string& type = "TEXT");
// --<name> A,B,...: comma-separated words (empty ones dropped), at least one.
CLI::Option* add_words(CLI::App& app, const std::string& name, std::vector<std::string>* target,
                       const std::string& help, const std::string& type = "A,B,...");
// --<name> x,y,z: three finite numbers.
CLI::Option* add_point(CLI::App& app, const std::string& name, std::optional<Eigen::Vector3d>* target,
                       const std::string& help);
// --<name>: a flag, false unless given (given twice: an error).
CLI::Option* add_flag(CLI::App& app, const std::string& name, bool* target, const std::string& help);

}  // namespace pbnbv::cli
