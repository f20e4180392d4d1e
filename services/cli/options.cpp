#include "cli/options.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include "core/base/version.hpp"

namespace pbnbv::cli {

namespace {

constexpr const char* kSettingsFileOption = "--config";

// Edit distance (insertions, deletions, substitutions) between a and b.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// The option of `app` whose long name is closest to `name`: at most 2 edits away ("veiws" ->
// "views"), else the longest name `name` starts with ("mesh-file" -> "mesh"); "" when none.
std::string closest_option(const CLI::App& app, const std::string& name) {
  std::string best, longest_prefix;
  std::size_t best_distance = 3;
  for (const CLI::Option* o : app.get_options()) {
    for (const std::string& candidate : o->get_lnames()) {
      const std::size_t d = edit_distance(name, candidate);
      if (d < best_distance) {
        best_distance = d;
        best = candidate;
      }
      // "mesh-file" -> "mesh": the longest option name the word starts with.
      if (name.rfind(candidate, 0) == 0 && candidate.size() > longest_prefix.size()) longest_prefix = candidate;
    }
  }
  return best.empty() ? longest_prefix : best;
}

// " (did you mean --views?)", or " (did you mean views?)" for a settings file (prefix "").
std::string did_you_mean(const CLI::App& app, const std::string& name, const std::string& prefix = "--") {
  const std::string close = closest_option(app, name);
  return close.empty() ? std::string() : " (did you mean " + prefix + close + "?)";
}

// The apps given on the command line: the program, then each command in turn.
std::vector<CLI::App*> selected_chain(CLI::App& app) {
  std::vector<CLI::App*> chain{&app};
  while (!chain.back()->get_subcommands().empty()) chain.push_back(chain.back()->get_subcommands().front());
  return chain;
}

// "pbnbv scan": the names along the chain, for messages.
std::string chain_name(const std::vector<CLI::App*>& chain) {
  std::string name;
  for (const CLI::App* a : chain) name += (name.empty() ? "" : " ") + a->get_name();
  return name;
}

// "-x", "--name", "--name=value"; not a negative number ("-0.5").
bool looks_like_option(const std::string& word) {
  double number = 0;
  return word.size() > 1 && word[0] == '-' && !detail::parse_number(word, &number);
}

// Throws std::invalid_argument for the first word no option or command took: an unknown option
// (with the closest known one), an unknown command, or a stray word.
void reject_leftovers(const std::vector<CLI::App*>& chain) {
  for (CLI::App* a : chain) {
    const std::vector<std::string> rest = a->remaining(false);
    if (rest.empty()) continue;
    for (const std::string& word : rest) {
      if (!looks_like_option(word)) continue;
      const std::string name = word.substr(0, word.find('='));
      const std::string bare = name.substr(name.find_first_not_of('-'));
      throw std::invalid_argument("unknown option " + name + did_you_mean(*a, bare));
    }
    const std::vector<CLI::App*> commands_of_a = a->get_subcommands([](CLI::App*) { return true; });
    if (chain.size() == 1 && !commands_of_a.empty()) {
      std::string commands;
      for (const CLI::App* c : commands_of_a) commands += (commands.empty() ? "" : ", ") + c->get_name();
      throw std::invalid_argument("unknown command '" + rest.front() + "' (expected " + commands + ")");
    }
    throw std::invalid_argument("unexpected argument '" + rest.front() + "' (options look like --name value)");
  }
}

// CLI11's "--views: At Most 1 required but received 2" and "--views: 1 required N missing" in
// our words, naming the option.
std::string mismatch_message(const std::vector<CLI::App*>& chain, const std::string& what) {
  const std::string name = what.substr(0, what.find(':'));
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const CLI::Option* o = (*it)->get_option_no_throw(name);
    if (o == nullptr) continue;
    if (o->count() > 1) {
      std::string values;
      if (o->get_expected_max() > 0) {
        for (const std::string& v : o->results()) values += (values.empty() ? " (" : ", ") + v;
        values += ")";
      }
      return name + " is given " + std::to_string(o->count()) + " times" + values + ": give it once";
    }
    return name + " needs a value";
  }
  return what;
}

// The name of the validator detail::takes() adds for `k`.
const char* kind_name(detail::ValueKind k) {
  using detail::ValueKind;
  switch (k) {
    case ValueKind::kNumber: return "takes:number";
    case ValueKind::kText: return "takes:text";
    case ValueKind::kList: return "takes:list";
    case ValueKind::kPoint: return "takes:point";
    case ValueKind::kBool: return "takes:bool";
  }
  return "takes:text";
}

// What `o` takes from a settings file (detail::takes); text when unmarked.
detail::ValueKind kind_of(CLI::Option* o) {
  using detail::ValueKind;
  for (const ValueKind k : {ValueKind::kNumber, ValueKind::kList, ValueKind::kPoint, ValueKind::kBool}) {
    try {
      if (o->get_validator(kind_name(k)) != nullptr) return k;
    } catch (const CLI::Error&) {
    }
  }
  return ValueKind::kText;
}

// TOML's type of a value as written: a quoted string, an array, true/false, else a number (a
// bare word, which TOML does not allow, counts as text).
enum class Written { kString, kArray, kBool, kNumber, kBare };

Written written(const std::string& raw) {
  if (raw.empty()) return Written::kBare;
  if (raw[0] == '"' || raw[0] == '\'') return Written::kString;
  if (raw[0] == '[') return Written::kArray;
  std::string word = raw.substr(0, raw.find_first_of(" \t#"));
  if (word == "true" || word == "false") return Written::kBool;
  double number = 0;
  std::string plain;
  for (const char c : word) {
    if (c != '_') plain += c;  // TOML allows 1_000
  }
  return detail::parse_number(plain, &number) ? Written::kNumber : Written::kBare;
}

const char* written_name(Written w) {
  switch (w) {
    case Written::kString: return "a string";
    case Written::kArray: return "an array";
    case Written::kBool: return "true/false";
    case Written::kNumber: return "a number";
    case Written::kBare: return "a bare word";
  }
  return "?";
}

// The raw value text of each top-level `name = value` line of a TOML file (what follows the '=',
// trimmed), for the types CLI11's reader does not keep ("3" and 3 both reach it as 3).
std::map<std::string, std::string> raw_values(const std::string& path) {
  std::map<std::string, std::string> out;
  std::ifstream in(path);
  std::string line;
  bool in_section = false;
  while (std::getline(in, line)) {
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    if (line[first] == '[') {
      in_section = true;
      continue;
    }
    const std::size_t eq = line.find('=');
    if (in_section || eq == std::string::npos) continue;
    std::string key = line.substr(first, eq - first);
    key.erase(key.find_last_not_of(" \t") + 1);
    if (key.size() >= 2 && (key.front() == '"' || key.front() == '\'') && key.back() == key.front()) {
      key = key.substr(1, key.size() - 2);
    }
    const std::size_t v = line.find_first_not_of(" \t", eq + 1);
    out[key] = v == std::string::npos ? "" : line.substr(v);
  }
  return out;
}

// "" when a value written as `w` suits an option taking `k`; else what the option takes.
std::string mismatch(detail::ValueKind k, Written w) {
  using detail::ValueKind;
  switch (k) {
    case ValueKind::kNumber:
      return w == Written::kNumber ? "" : "a number (unquoted)";
    case ValueKind::kText:
      return w == Written::kString ? "" : "a quoted string";
    case ValueKind::kList:
      return w == Written::kArray || w == Written::kString ? "" : "an array of quoted names, or one \"a,b\" string";
    case ValueKind::kPoint:
      return w == Written::kArray || w == Written::kString ? "" : "an array of three numbers [x, y, z]";
    case ValueKind::kBool:
      return w == Written::kBool ? "" : "true or false (unquoted)";
  }
  return "";
}

}  // namespace

namespace detail {

std::string missing_value(const std::string& text) {
  if (text.rfind("--", 0) == 0) return "missing value (the next word, '" + text + "', is an option)";
  if (text.empty()) return "missing value (empty)";
  return "";
}

bool parse_number(const std::string& text, long long* v) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return false;
  errno = 0;
  char* end = nullptr;
  *v = std::strtoll(text.c_str(), &end, 10);
  return errno != ERANGE && end == text.c_str() + text.size();
}

bool parse_number(const std::string& text, double* v) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return false;
  errno = 0;
  char* end = nullptr;
  *v = std::strtod(text.c_str(), &end);
  return errno != ERANGE && end == text.c_str() + text.size() && std::isfinite(*v);
}

std::string type_name(std::string_view unit, bool integral) {
  if (unit.empty()) return integral ? "N" : "X";
  std::string t(unit);
  std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return t;
}

std::vector<std::string> split_list(const std::string& text, char separator) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(separator, start), text.size());
    if (end > start) out.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

std::optional<std::vector<double>> parse_numbers(const std::string& text, std::size_t count) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    parts.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (parts.size() != count) return std::nullopt;
  std::vector<double> v(count);
  for (std::size_t i = 0; i < count; ++i) {
    if (!parse_number(parts[i], &v[i])) return std::nullopt;
  }
  return v;
}

std::optional<Eigen::Vector3d> parse_point(const std::string& text) {
  const std::optional<std::vector<double>> v = parse_numbers(text, 3);
  if (!v) return std::nullopt;
  return Eigen::Vector3d((*v)[0], (*v)[1], (*v)[2]);
}

CLI::Option* takes(CLI::Option* o, ValueKind kind) {
  o->check(CLI::Validator([](std::string&) { return std::string(); }, "", kind_name(kind)));
  return o;
}

CLI::Option* finish(CLI::Option* o, const std::string& type) {
  o->type_name(type);
  o->multi_option_policy(CLI::MultiOptionPolicy::Throw);
  return o;
}

}  // namespace detail

void init(CLI::App& app) {
  app.set_version_flag("--version", app.get_name() + " " + std::string(pbnbv_version()), "print the version and exit");
  app.allow_extras();  // unknown options are reported by parse(), naming the closest known one
  app.get_formatter()->column_width(32);
}

CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& description) {
  CLI::App* c = app.add_subcommand(name, description);
  c->allow_extras();
  return c;
}

std::optional<int> parse(CLI::App& app, int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  auto fail = [&](const std::string& message) {
    const std::vector<CLI::App*> chain = selected_chain(app);
    err << chain_name(chain) << ": " << message << "\n(" << chain_name(chain) << " --help lists the options)" << std::endl;
    return 2;
  };
  try {
    app.parse(argc, argv);
    const std::vector<CLI::App*> chain = selected_chain(app);
    reject_leftovers(chain);
    for (CLI::App* a : chain) {
      const CLI::Option* file = a->get_option_no_throw(kSettingsFileOption);
      if (file != nullptr && file->count() > 0) apply_settings_file(*a, file->as<std::string>());
    }
  } catch (const CLI::CallForHelp&) {
    // A program with commands describes every command when asked without one.
    const bool whole = selected_chain(app).size() == 1 && !app.get_subcommands([](CLI::App*) { return true; }).empty();
    out << (whole ? app.get_formatter()->make_help(&app, app.get_name(), CLI::AppFormatMode::All) : app.help());
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    out << app.help("", CLI::AppFormatMode::All);
    return 0;
  } catch (const CLI::CallForVersion& e) {
    out << e.what() << std::endl;
    return 0;
  } catch (const CLI::ArgumentMismatch& e) {
    return fail(mismatch_message(selected_chain(app), e.what()));
  } catch (const CLI::ParseError& e) {
    return fail(e.what());
  } catch (const std::invalid_argument& e) {
    return fail(e.what());
  }
  return std::nullopt;
}

CLI::Option* add_settings_file(CLI::App& command) {
  return command
      .add_option(kSettingsFileOption, "read options from this TOML file (name = value lines, names without --); "
                                       "options on the command line override the file")
      ->type_name("FILE")
      ->check(CLI::Validator([](std::string& text) { return detail::missing_value(text); }, ""))
      ->multi_option_policy(CLI::MultiOptionPolicy::Throw);
}

void apply_settings_file(CLI::App& command, const std::string& path) {
  const std::string where = std::string(kSettingsFileOption) + " " + path;
  if (!std::filesystem::is_regular_file(path)) throw std::invalid_argument(where + ": no such file");
  std::vector<CLI::ConfigItem> items;
  try {
    items = CLI::ConfigTOML().from_file(path);
  } catch (const CLI::Error& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
  const std::map<std::string, std::string> raw = raw_values(path);
  for (const CLI::ConfigItem& item : items) {
    // CLI11 marks the start and end of a [section] with the names "++" and "--".
    if (!item.parents.empty() || item.name == "++" || item.name == "--") {
      std::string section;
      for (const std::string& p : item.parents) section += (section.empty() ? "" : ".") + p;
      throw std::invalid_argument(where + ": [" + section +
                                  "]: sections are not read; write each option as a name = value line");
    }
    const std::string name = "--" + item.name;
    CLI::Option* o = command.get_option_no_throw(name);
    if (o == nullptr || name == kSettingsFileOption || name == "--help" || name == "--version") {
      throw std::invalid_argument(where + ": unknown setting '" + item.name + "'" + did_you_mean(command, item.name, ""));
    }
    const auto line = raw.find(item.name);
    if (line != raw.end()) {
      const Written w = written(line->second);
      const std::string wanted = mismatch(kind_of(o), w);
      if (!wanted.empty()) {
        throw std::invalid_argument(where + ": " + item.name + " = " + line->second + ": " + written_name(w) +
                                    " where " + item.name + " takes " + wanted);
      }
    }
    if (o->count() > 0) continue;  // the command line wins
    std::string value;
    for (const std::string& v : item.inputs) value += (value.empty() ? "" : ",") + v;
    try {
      o->add_result(value);
      o->run_callback();
    } catch (const CLI::Error& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
  }
}

CLI::Option* add_text(CLI::App& app, const std::string& name, std::string* target, const std::string& help,
                      const std::string& type) {
  auto* o = app.add_option_function<std::string>(
      "--" + name, [target](const std::string& text) { *target = text; },
      target->empty() ? help : help + " [" + *target + "]");
  o->check(CLI::Validator([](std::string& text) { return detail::missing_value(text); }, ""));
  return detail::finish(o, type);
}

CLI::Option* add_words(CLI::App& app, const std::string& name, std::vector<std::string>* target,
                       const std::string& help, const std::string& type) {
  auto* o = app.add_option_function<std::string>(
      "--" + name, [target](const std::string& text) { *target = detail::split_list(text); }, help);
  o->check(CLI::Validator(
      [](std::string& text) -> std::string {
        const std::string missing = detail::missing_value(text);
        if (!missing.empty()) return missing;
        return detail::split_list(text).empty() ? "'" + text + "' lists nothing" : "";
      },
      ""));
  detail::takes(o, detail::ValueKind::kList);
  return detail::finish(o, type);
}

CLI::Option* add_point(CLI::App& app, const std::string& name, std::optional<Eigen::Vector3d>* target,
                       const std::string& help) {
  auto* o = app.add_option_function<std::string>(
      "--" + name, [target](const std::string& text) { *target = detail::parse_point(text); }, help);
  o->check(CLI::Validator(
      [](std::string& text) -> std::string {
        const std::string missing = detail::missing_value(text);
        if (!missing.empty()) return missing;
        return detail::parse_point(text) ? "" : "'" + text + "' is not three numbers x,y,z";
      },
      ""));
  detail::takes(o, detail::ValueKind::kPoint);
  return detail::finish(o, "x,y,z");
}

CLI::Option* add_flag(CLI::App& app, const std::string& name, bool* target, const std::string& help) {
  *target = false;
  return detail::takes(app.add_flag("--" + name, *target, help), detail::ValueKind::kBool)
      ->multi_option_policy(CLI::MultiOptionPolicy::Throw);
}

}  // namespace pbnbv::cli
