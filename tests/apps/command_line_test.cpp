// apps/support/command_line.h (CLI11 with the programs' conventions), in process: what the
// validators accept, the values they hand on, their messages, parse()'s one-line errors and
// --help; then every program's --help and a mistake of each, run as a command.
#include <gtest/gtest.h>

#include "support/command_line.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "common/run_command.h"

namespace cdp::app {
namespace {

struct Outcome {
  std::optional<int> status;  // parse()'s answer
  std::string out, err;
};

// `program --x TEXT` with the option --x checked by `check`, parsed into `value`.
template <class T>
Outcome parse_x(const CLI::Validator& check, const std::vector<std::string>& args, T& value) {
  CLI::App app{"A test program.", "prog"};
  configure(app);
  app.add_option("--x", value, "the option")->transform(check);
  std::vector<const char*> argv{"prog"};
  for (const auto& a : args) argv.push_back(a.c_str());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  Outcome o;
  o.status = parse(app, static_cast<int>(argv.size()), argv.data());
  o.out = testing::internal::GetCapturedStdout();
  o.err = testing::internal::GetCapturedStderr();
  return o;
}

template <class T>
void expect_value(const CLI::Validator& check, const std::string& text, T expected) {
  T value{};
  const Outcome o = parse_x(check, {"--x", text}, value);
  EXPECT_FALSE(o.status) << text << ": " << o.err;
  EXPECT_EQ(value, expected) << text;
}

template <class T = double>
void expect_refused(const CLI::Validator& check, const std::string& text, const std::string& message) {
  T value{};
  const Outcome o = parse_x(check, {"--x", text}, value);
  EXPECT_EQ(o.status, 1) << text;
  EXPECT_EQ(o.err, "prog: --x: " + message + "\n") << text;
  EXPECT_EQ(o.out, "");
}

TEST(CommandLine, NumbersAreReadCorrectlyRounded) {
  // CLI11 alone reads through long double and rounds this decimal twice, one ulp off.
  const char* twice = "873940.419253";
  ASSERT_NE(static_cast<double>(std::strtold(twice, nullptr)), std::strtod(twice, nullptr));
  expect_value(number(), twice, std::strtod(twice, nullptr));
  expect_value(number(), "0.1", 0.1);
  expect_value(number(), "-2.5e-3", -2.5e-3);
  expect_value(number(), "+3", 3.0);
  expect_value(number(), "1e-310", 1e-310);  // subnormal
  expect_value(number(), "1.7976931348623157e308", 1.7976931348623157e308);
  double zero = 1;
  EXPECT_FALSE(parse_x(number(), {"--x", "-0"}, zero).status);
  EXPECT_TRUE(zero == 0 && std::signbit(zero));
  expect_value(positive_number(), "5e-324", 5e-324);
  expect_value(number_in(-90, 90), "-90", -90.0);
}

TEST(CommandLine, WhatIsNotAFiniteNumberIsRefusedWithTheText) {
  expect_refused(number(), "two", "expects a number, found \"two\"");
  expect_refused(number(), "", "expects a number, found \"\"");
  expect_refused(number(), "1,5", "expects a number, found \"1,5\"");
  expect_refused(number(), "0x10", "expects a number, found \"0x10\"");
  expect_refused(number(), " 3", "expects a number, found \" 3\"");
  expect_refused(number(), "nan", "expects a number, found \"nan\", which is not finite");
  expect_refused(number(), "-inf", "expects a number, found \"-inf\", which is not finite");
  expect_refused(number(), "1e999", "expects a number, found \"1e999\", which is beyond double precision");
  expect_refused(positive_number(), "0", "expects a positive number, found \"0\"");
  expect_refused(positive_number(), "-1", "expects a positive number, found \"-1\"");
  expect_refused(positive_number(), "inf", "expects a positive number, found \"inf\", which is not finite");
  expect_refused(number_in(-90, 90), "90.5", "expects a number between -90 and 90, found \"90.5\"");
  expect_refused(number_in(0.5, 1e300), "0", "expects a number between 0.5 and 1e+300, found \"0\"");
}

TEST(CommandLine, IntegersAreDecimalAndWithinTheirRange) {
  expect_value(integer_in(0, 100), "010", 10);  // not octal, as CLI11 alone would read it
  expect_value(integer_in(0, 100), "1e1", 10);
  expect_value(integer_in(0, 100), "7.0", 7);
  expect_value(integer_in(-5, 5), "-5", -5);
  expect_value(integer_in(1, 2147483647), "2147483647", 2147483647);
  expect_value<std::size_t>(integer_in(1, 100000000), "100000000", 100000000);
  expect_refused<int>(integer_in(0, 5), "6", "expects an integer between 0 and 5, found \"6\"");
  expect_refused<int>(integer_in(0, 5), "1.5", "expects an integer between 0 and 5, found \"1.5\"");
  expect_refused<int>(integer_in(0, 5), "three", "expects an integer between 0 and 5, found \"three\"");
  expect_refused<int>(integer_in(2, 2147483647), "2147483648",
                      "expects an integer between 2 and 2147483647, found \"2147483648\"");
  expect_refused<int>(integer_in(1, 8), "nan", "expects an integer between 1 and 8, found \"nan\", which is not finite");
}

TEST(CommandLine, ListsOfNumbersHaveTheirCount) {
  std::string text;
  EXPECT_FALSE(parse_x(numbers(3, "x,y,z"), {"--x", "1, -2 ,3e1"}, text).status);
  EXPECT_EQ(split_numbers(text), (std::vector<double>{1, -2, 30}));
  for (const std::string bad : {"1,2", "1,2,3,4", "1,,3", "1,nan,3", "", ",1,2", "1,2,3,"})
    expect_refused<std::string>(numbers(3, "x,y,z"), bad, "expects three numbers x,y,z, found \"" + bad + "\"");
  expect_refused<std::string>(numbers(2, "LO,HI"), "1", "expects two numbers LO,HI, found \"1\"");
  expect_refused<std::string>(non_empty("a property name"), "", "expects a property name, found \"\"");
}

TEST(CommandLine, MistakesInTheShapeOfTheCommandLineAreOneLine) {
  int value = 0;
  const struct {
    std::vector<std::string> args;
    std::string message;
  } cases[] = {
      {{"--x", "1", "--x", "2"}, "--x given twice"},
      {{"--x", "1", "--x", "2", "--x", "3"}, "--x given 3 times"},
      {{"--x"}, "--x needs a value; see prog --help"},
      {{"--y"}, "The following argument was not expected: --y; see prog --help"},
      {{"extra"}, "The following argument was not expected: extra; see prog --help"},
  };
  for (const auto& c : cases) {
    const Outcome o = parse_x(integer_in(0, 9), c.args, value);
    EXPECT_EQ(o.status, 1) << c.message;
    EXPECT_EQ(o.err, "prog: " + c.message + "\n");
    EXPECT_EQ(o.out, "");
  }
}

TEST(CommandLine, HelpGoesToStandardOutputWithStatusZero) {
  int value = 0;
  for (const std::string flag : {"--help", "-h"}) {
    const Outcome o = parse_x(integer_in(0, 9), {flag}, value);
    EXPECT_EQ(o.status, 0);
    EXPECT_EQ(o.err, "");
    EXPECT_NE(o.out.find("A test program."), std::string::npos) << o.out;
    EXPECT_NE(o.out.find("Usage: prog [OPTIONS]"), std::string::npos) << o.out;
    EXPECT_NE(o.out.find("--x"), std::string::npos) << o.out;
  }
}

// ---- The programs ----------------------------------------------------------------------------

const char* const kPrograms[] = {"polygonize", "evaluate", "render", "curvature", "experiment"};

TEST(CommandLineApps, EveryProgramPrintsItsHelpOnStandardOutput) {
  for (const std::string program : kPrograms)
    for (const char* flag : {"--help", "-h"}) {
      const auto r = test::run_app(program, flag);
      EXPECT_EQ(r.exit_code, 0) << program << " " << flag;
      EXPECT_EQ(r.err, "") << program << " " << flag;
      EXPECT_NE(r.out.find("\nUsage: " + program + " [OPTIONS]"), std::string::npos) << r.out;
      EXPECT_NE(r.out.find("-h,--help"), std::string::npos) << r.out;
    }
  // polygonize sorts its options by method.
  const std::string help = test::run_app("polygonize", "--help").out;
  for (const char* text : {"adaptive method", "--factor K", "--tolerance EPS", "--chord EPS", "mc and mt methods", "--cell H",
                           "--precision P", "--seed-resolution N"})
    EXPECT_NE(help.find(text), std::string::npos) << text << "\n" << help;
  EXPECT_LT(help.find("adaptive method"), help.find("--factor K"));
  EXPECT_LT(help.find("--factor K"), help.find("mc and mt methods"));
  EXPECT_GT(help.find("--cell H"), help.find("mc and mt methods"));
}

TEST(CommandLineApps, MistakesFoundByCli11AreOneLineWithStatusOne) {
  test::TempDir dir("command_line_apps");
  const std::string f = (dir.path / "f.json").string(), m = (dir.path / "m.ply").string();
  const std::string out = (dir.path / "out.ply").string(), png = (dir.path / "p.png").string();
  const std::string json = (dir.path / "m.json").string();
  const struct {
    std::string program, args, message;
  } cases[] = {
      {"polygonize", f + " -o " + out + " --bogus", "The following argument was not expected: --bogus; see polygonize --help"},
      {"polygonize", f, "--output is required; see polygonize --help"},
      {"polygonize", "-o " + out, "FIELD.json is required; see polygonize --help"},
      {"polygonize", f + " -o " + out + " -o " + out, "--output given twice"},
      {"polygonize", f + " -o " + out + " --factor inf", "--factor: expects a positive number, found \"inf\", which is not finite"},
      {"polygonize", f + " -o " + out + " --method mt --precision 1.5",
       "--precision: expects an integer between 0 and 5, found \"1.5\""},
      {"polygonize", f + " -o " + out + " --method MC", "--method: MC not in {adaptive,mc,mt}"},
      {"evaluate", f + " " + m + " -o " + json + " --rays", "--rays needs a value; see evaluate --help"},
      {"evaluate", f + " " + m + " -o " + json + " --views 1 --views 2", "--views given twice"},
      {"evaluate", f + " " + m + " " + m + " -o " + json, "The following argument was not expected: " + m + "; see evaluate --help"},
      {"render", m + " -o " + png + " --zoom nan", "--zoom: expects a positive number, found \"nan\", which is not finite"},
      {"render", m + " -o " + png + " --elevation 91", "--elevation: expects a number between -90 and 90, found \"91\""},
      {"render", m + " -o " + png + " --range 1", "--range: expects two numbers LO,HI, found \"1\""},
      {"curvature", f + " --at 1,2", "--at: expects three numbers x,y,z, found \"1,2\""},
      {"curvature", f + " --at", "--at needs a value; see curvature --help"},
      {"experiment", f + " --jobs 0", "--jobs: expects an integer between 1 and 2147483647, found \"0\""},
      {"experiment", f + " --run", "--run needs a value; see experiment --help"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_app(c.program, c.args);
    EXPECT_EQ(r.exit_code, 1) << c.program << " " << c.args;
    EXPECT_EQ(r.err, c.program + ": " + c.message + "\n") << c.program << " " << c.args;
    EXPECT_EQ(r.out, "") << c.program << " " << c.args;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path));
}

}  // namespace
}  // namespace cdp::app
