// The command line every program shares: options from the settings table, errors that name the
// option (missing value, given twice, not a number, out of range, unknown, not one of the
// names), --help / --version, and settings files that the command line overrides.
#include "cli/options.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace pbnbv {

enum class Colour { kRed, kGreen, kBlue };
template <>
struct EnumNames<Colour> {
  static constexpr std::string_view what = "colour";
  static constexpr std::array<NamedValue<Colour>, 3> names{
      {{Colour::kRed, "red"}, {Colour::kGreen, "green"}, {Colour::kBlue, "blue"}}};
};

namespace {

constexpr Setting<int> kCount{"views", 10, 1, 1000, "", "at most this many views"};
constexpr Setting<double> kSize{"size", 0.3, 0.01, 2.0, "m", "object size"};
constexpr ChoiceSetting<Colour> kColour{"colour", Colour::kGreen, "the colour"};

// A program with a few options of every kind, parsed from words.
struct Program {
  CLI::App app{"test program", "prog"};
  int views = 0;
  double size = 0;
  Colour colour = Colour::kRed;
  std::vector<Colour> palette = {Colour::kRed};
  std::optional<Eigen::Vector3d> point;
  std::string out;
  bool quiet = false;
  std::ostringstream out_text, err_text;

  explicit Program(bool with_file = false) {
    cli::init(app);
    cli::add(app, kCount, &views);
    cli::add(app, kSize, &size);
    cli::add(app, kColour, &colour);
    cli::add_list(app, "palette", &palette, "colours");
    cli::add_point(app, "point", &point, "a point");
    cli::add_text(app, "out", &out, "output folder", "DIR");
    cli::add_flag(app, "quiet", &quiet, "say less");
    if (with_file) cli::add_settings_file(app);
  }

  std::optional<int> parse(std::vector<std::string> words) {
    words.insert(words.begin(), "prog");
    std::vector<const char*> argv;
    for (const auto& w : words) argv.push_back(w.c_str());
    return cli::parse(app, static_cast<int>(argv.size()), argv.data(), out_text, err_text);
  }
};

// The error a command line gets (exit code 2 checked).
std::string error_of(std::vector<std::string> words) {
  Program p;
  const std::optional<int> code = p.parse(std::move(words));
  EXPECT_EQ(code, std::optional<int>(2));
  return p.err_text.str();
}

std::string settings_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("pbnbv-options-test-" + name + ".toml");
  std::ofstream(path) << text;
  return path.string();
}

TEST(Options, DefaultsComeFromTheTableAndValuesAreRead) {
  Program p;
  ASSERT_EQ(p.parse({}), std::nullopt);
  EXPECT_EQ(p.views, 10);
  EXPECT_DOUBLE_EQ(p.size, 0.3);
  EXPECT_EQ(p.colour, Colour::kGreen);
  EXPECT_FALSE(p.point.has_value());
  EXPECT_FALSE(p.quiet);
  Program q;
  ASSERT_EQ(q.parse({"--views", "3", "--size=0.25", "--colour", "blue", "--palette", "blue,red", "--point", "-0.5,0,0.9",
                     "--out", "x", "--quiet"}),
            std::nullopt)
      << q.err_text.str();
  EXPECT_EQ(q.views, 3);
  EXPECT_DOUBLE_EQ(q.size, 0.25);
  EXPECT_EQ(q.colour, Colour::kBlue);
  EXPECT_EQ(q.palette, (std::vector<Colour>{Colour::kBlue, Colour::kRed}));
  ASSERT_TRUE(q.point.has_value());
  EXPECT_EQ(*q.point, Eigen::Vector3d(-0.5, 0, 0.9));
  EXPECT_EQ(q.out, "x");
  EXPECT_TRUE(q.quiet);
}

TEST(Options, ErrorsNameTheOption) {
  EXPECT_EQ(error_of({"--views"}), "prog: --views needs a value\n(prog --help lists the options)\n");
  EXPECT_NE(error_of({"--out", "--views", "3"}).find("--out: missing value (the next word, '--views', is an option)"),
            std::string::npos);
  EXPECT_NE(error_of({"--views", "3", "--views", "4"}).find("--views is given 2 times (3, 4): give it once"),
            std::string::npos);
  EXPECT_NE(error_of({"--quiet", "--quiet"}).find("--quiet is given 2 times"), std::string::npos);
  EXPECT_NE(error_of({"--views", "2000"}).find("--views: 2000 is outside its range [1, 1000]"), std::string::npos);
  EXPECT_NE(error_of({"--views", "0"}).find("--views: 0 is outside its range [1, 1000]"), std::string::npos);
  EXPECT_NE(error_of({"--views", "3.5"}).find("--views: '3.5' is not a whole number"), std::string::npos);
  EXPECT_NE(error_of({"--size", "7"}).find("--size: 7 is outside its range [0.01, 2] m"), std::string::npos);
  EXPECT_NE(error_of({"--size", "nan"}).find("--size: 'nan' is not a number"), std::string::npos);
  EXPECT_NE(error_of({"--colour", "Blue"}).find("--colour: unknown colour 'Blue' (expected red, green or blue)"),
            std::string::npos);
  EXPECT_NE(error_of({"--palette", "red,red"}).find("--palette: 'red' is listed twice"), std::string::npos);
  EXPECT_NE(error_of({"--palette", ","}).find("--palette: ',' names no colour"), std::string::npos);
  EXPECT_NE(error_of({"--point", "1,2"}).find("--point: '1,2' is not three numbers x,y,z"), std::string::npos);
  EXPECT_NE(error_of({"--veiws", "3"}).find("unknown option --veiws (did you mean --views?)"), std::string::npos);
  EXPECT_NE(error_of({"--frobnicate=2"}).find("unknown option --frobnicate\n"), std::string::npos);
  EXPECT_NE(error_of({"stray"}).find("unexpected argument 'stray'"), std::string::npos);
}

TEST(Options, HelpAndVersionExitZero) {
  Program p;
  EXPECT_EQ(p.parse({"--help"}), std::optional<int>(0));
  const std::string help = p.out_text.str();
  EXPECT_NE(help.find("--views N"), std::string::npos) << help;
  EXPECT_NE(help.find("at most this many views [10] (range [1, 1000])"), std::string::npos) << help;
  EXPECT_NE(help.find("--size M"), std::string::npos) << help;
  EXPECT_NE(help.find("object size [0.3 m] (range [0.01, 2] m)"), std::string::npos) << help;
  EXPECT_NE(help.find("--colour red|green|blue"), std::string::npos) << help;
  Program v;
  EXPECT_EQ(v.parse({"--version"}), std::optional<int>(0));
  EXPECT_EQ(v.out_text.str(), std::string("prog ") + PBNBV_TEST_VERSION + "\n");
}

TEST(Options, ASettingsFileFillsWhatTheCommandLineLeaves) {
  const std::string file = settings_file("ok", "# a comment\nviews = 3\ncolour = \"blue\"\npoint = [0.9, 0, 0]\nquiet = true\n");
  Program p(true);
  ASSERT_EQ(p.parse({"--config", file, "--views", "5"}), std::nullopt) << p.err_text.str();
  EXPECT_EQ(p.views, 5);  // the command line wins
  EXPECT_EQ(p.colour, Colour::kBlue);
  ASSERT_TRUE(p.point.has_value());
  EXPECT_EQ(*p.point, Eigen::Vector3d(0.9, 0, 0));
  EXPECT_TRUE(p.quiet);
  EXPECT_DOUBLE_EQ(p.size, 0.3);  // in neither: the default
}

TEST(Options, ASettingsFileIsCheckedLikeTheCommandLine) {
  auto error = [](const std::string& name, const std::string& text) {
    const std::string file = settings_file(name, text);
    Program p(true);
    EXPECT_EQ(p.parse({"--config", file}), std::optional<int>(2));
    const std::string e = p.err_text.str();
    EXPECT_NE(e.find("--config " + file + ": "), std::string::npos) << e;
    return e;
  };
  EXPECT_NE(error("typo", "veiws = 3\n").find("unknown setting 'veiws' (did you mean views?)"), std::string::npos);
  EXPECT_NE(error("range", "views = 3000\n").find("--views: 3000 is outside its range [1, 1000]"), std::string::npos);
  EXPECT_NE(error("choice", "colour = \"pink\"\n").find("unknown colour 'pink'"), std::string::npos);
  EXPECT_NE(error("section", "[scan]\nviews = 3\n").find("[scan]: sections are not read"), std::string::npos);
  // A value of the wrong TOML type names the file, the key and what it takes.
  EXPECT_NE(error("quoted", "views = \"3\"\n").find("views = \"3\": a string where views takes a number (unquoted)"),
            std::string::npos);
  EXPECT_NE(error("flag", "quiet = \"yes\"\n").find("quiet = \"yes\": a string where quiet takes true or false"),
            std::string::npos);
  EXPECT_NE(error("flag-number", "quiet = 1\n").find("quiet = 1: a number where quiet takes true or false"),
            std::string::npos);
  EXPECT_NE(error("choice-bare", "colour = 3\n").find("colour = 3: a number where colour takes a quoted string"),
            std::string::npos);
  EXPECT_NE(error("point", "point = 0.9\n").find("point = 0.9: a number where point takes an array of three numbers"),
            std::string::npos);
  EXPECT_NE(error("size", "size = true\n").find("size = true: true/false where size takes a number"), std::string::npos);
  Program p(true);
  EXPECT_EQ(p.parse({"--config", "/nonexistent/pbnbv.toml"}), std::optional<int>(2));
  EXPECT_NE(p.err_text.str().find("--config /nonexistent/pbnbv.toml: no such file"), std::string::npos);
}

}  // namespace
}  // namespace pbnbv
