// apps/support/command_line.h (CLI11 with the programs' conventions), in process: what the
// validators accept, the values they hand on, their messages, parse()'s one-line errors and
// --help.
#include <gtest/gtest.h>

#include "support/command_line.h"

#include <cmath>
#include <cstdlib>

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

}  // namespace
}  // namespace cdp::app
