// The programs' command lines, parsed with CLI11, and the conventions they share: every option
// at most once, numbers that are finite and within their range, `--help` on standard output
// with status 0, and any mistake reported as one line "program: message" with status 1.
#pragma once

#include <CLI/CLI.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace cdp::app {

// Sets the conventions on a fresh app (before its options are added): an option given twice
// is an error (MultiOptionPolicy::Throw) rather than a silent replacement of the first value.
void configure(CLI::App& app);

// Parses the command line. std::nullopt: go on. Otherwise the program ends with the status
// returned: 0 after --help (the help is on standard output), 1 after a mistake (one line
// "NAME: message" on standard error, NAME being the app's name).
std::optional<int> parse(CLI::App& app, int argc, const char* const* argv);

// Validators for option values, with messages that name what was expected and what was found
// (CLI11 adds the option's name in front). CLI11's own number checks are not used: they accept
// "nan" (CLI::Range compares false both ways), print 309 digits for CLI::PositiveNumber's bound,
// read "010" as octal and convert through long double, which can round a decimal differently
// from the correctly rounded double of earlier versions. These four parse the text in decimal
// (std::from_chars) and replace it with an exact representation of the value they checked, so
// give them with ->transform(): ->check() would run them on a copy and let CLI11 convert the
// original text.
CLI::Validator number();                               // any finite number
CLI::Validator positive_number();                      // finite and > 0
CLI::Validator number_in(double lo, double hi);        // finite, within [lo, hi]
CLI::Validator integer_in(long long lo, long long hi); // an integer (1e3 and 7.0 count) within [lo, hi]
// `count` comma-separated finite numbers, e.g. numbers(3, "x,y,z") for a point; the option is
// a string, read with split_numbers() after parsing.
CLI::Validator numbers(std::size_t count, const std::string& form);
// Any text but the empty one, which is refused as "expects WHAT, found """.
CLI::Validator non_empty(const std::string& what);
CLI::Validator path_name();  // non_empty("a file name")

// The numbers of a text numbers() accepted.
std::vector<double> split_numbers(const std::string& text);

}  // namespace cdp::app
