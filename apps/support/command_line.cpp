#include "support/command_line.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <functional>
#include <system_error>

namespace cdp::app {

namespace {

enum class Reading { Ok, NotANumber, NotFinite, OutOfRange };

// The whole text as a decimal number, correctly rounded (a leading '+' allowed, no spaces).
Reading read_number(const std::string& text, double& value) {
  const char* first = text.data();
  const char* last = first + text.size();
  if (last - first > 1 && *first == '+' && first[1] != '-' && first[1] != '+') ++first;
  const auto [end, ec] = std::from_chars(first, last, value, std::chars_format::general);
  if (ec == std::errc::result_out_of_range && end == last) return Reading::OutOfRange;
  if (ec != std::errc() || end != last) return Reading::NotANumber;
  return std::isfinite(value) ? Reading::Ok : Reading::NotFinite;
}

std::string found(const std::string& text) { return ", found \"" + text + "\""; }

// "expects NOUN, found "TEXT"", and why when TEXT is a number of a kind ("inf", "1e999").
std::string expected(const std::string& noun, Reading r, const std::string& text) {
  const std::string message = "expects " + noun + found(text);
  if (r == Reading::NotFinite) return message + ", which is not finite";
  if (r == Reading::OutOfRange) return message + ", which is beyond double precision";
  return message;
}

// The comma-separated parts of a text, without spaces around them ("1, 2" reads as "1,2"; "1,,2"
// has an empty part).
std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const std::size_t comma = text.find(',', start);
    std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    part.erase(0, part.find_first_not_of(' '));
    part.erase(part.find_last_not_of(' ') + 1);
    parts.push_back(part);
    if (comma == std::string::npos) return parts;
    start = comma + 1;
  }
}

// CLI11 converts option values with strtold and a cast to double, which rounds some decimals
// twice ("873940.419253" ends one ulp off): it is given the checked value in hexadecimal, which
// both conversions keep exactly, so the options hold what std::from_chars read.
std::string exact(double v) {
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, std::abs(v), std::chars_format::hex);
  (void)ec;  // 64 characters hold any double
  return std::string(std::signbit(v) ? "-0x" : "0x") + std::string(buf, end);
}

// The shortest text that reads back as v, so that bounds print as they were written.
std::string format(double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  (void)ec;  // 32 characters hold any double
  return std::string(buf, end);
}

std::string count_word(std::size_t n) {
  static const char* const words[] = {"no", "one", "two", "three", "four"};
  return n < 5 ? words[n] : std::to_string(n);
}

void all_options(const CLI::App& app, std::vector<const CLI::Option*>& out) {
  for (const CLI::Option* o : app.get_options()) out.push_back(o);
  // Option groups are nameless subcommands holding their options.
  for (const CLI::App* group : app.get_subcommands([](const CLI::App* a) { return a->get_name().empty(); }))
    all_options(*group, out);
}

// CLI11 says "--out: At Most 1 required but received 2" for an option given twice and
// "--width: 1 required INT missing" for an option without its value; these say it plainly.
// Mistakes about the shape of the command line end with a pointer to the help.
std::string clearer(const CLI::App& app, const CLI::ParseError& e) {
  const std::string hint = "; see " + app.get_name() + " --help";
  const std::string message = e.what();
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e)) {
    std::vector<const CLI::Option*> options;
    all_options(app, options);
    for (const CLI::Option* o : options) {
      if (o->get_items_expected_max() < 1 || o->get_multi_option_policy() != CLI::MultiOptionPolicy::Throw) continue;
      const std::size_t n = o->count();
      if (n > static_cast<std::size_t>(o->get_items_expected_max()))
        return o->get_name() + " given " + (n == 2 ? std::string("twice") : std::to_string(n) + " times");
      if (n == 0 && message.rfind(o->get_name() + ": ", 0) == 0) return o->get_name() + " needs a value" + hint;
    }
  }
  if (dynamic_cast<const CLI::RequiredError*>(&e) || dynamic_cast<const CLI::ExtrasError*>(&e)) return message + hint;
  return message;
}

CLI::Validator validator(std::function<std::string(std::string&)> check) {
  // No description: the help text of each option says what it takes.
  return CLI::Validator(std::move(check), "");
}

}  // namespace

void configure(CLI::App& app) {
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::Throw);
  app.get_formatter()->column_width(32);
}

std::optional<int> parse(CLI::App& app, int argc, const char* const* argv) {
  try {
    app.parse(argc, argv);
    return std::nullopt;
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help: the help on standard output, status 0
  } catch (const CLI::ParseError& e) {
    std::string message = clearer(app, e);
    for (char& c : message)
      if (c == '\n') c = ' ';  // one line, whatever CLI11 says
    std::fprintf(stderr, "%s: %s\n", app.get_name().c_str(), message.c_str());
    return 1;
  }
}

CLI::Validator number() {
  return validator([](std::string& text) -> std::string {
    double v = 0;
    const Reading r = read_number(text, v);
    if (r != Reading::Ok) return expected("a number", r, text);
    text = exact(v);
    return {};
  });
}

CLI::Validator positive_number() {
  return validator([](std::string& text) -> std::string {
    double v = 0;
    const Reading r = read_number(text, v);
    if (r != Reading::Ok || !(v > 0)) return expected("a positive number", r, text);
    text = exact(v);
    return {};
  });
}

CLI::Validator number_in(double lo, double hi) {
  return validator([lo, hi](std::string& text) -> std::string {
    double v = 0;
    const Reading r = read_number(text, v);
    if (r != Reading::Ok || v < lo || v > hi)
      return expected("a number between " + format(lo) + " and " + format(hi), r, text);
    text = exact(v);
    return {};
  });
}

CLI::Validator integer_in(long long lo, long long hi) {
  return validator([lo, hi](std::string& text) -> std::string {
    double v = 0;
    const Reading r = read_number(text, v);
    // Doubles hold every integer of these ranges (all below 2^53) exactly.
    if (r != Reading::Ok || v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi))
      return expected("an integer between " + std::to_string(lo) + " and " + std::to_string(hi), r, text);
    // Plain decimal: CLI11 reads integers with base 0, where "010" would be octal.
    text = std::to_string(static_cast<long long>(v));
    return {};
  });
}

CLI::Validator numbers(std::size_t count, const std::string& form) {
  return validator([count, form](std::string& text) -> std::string {
    const std::vector<std::string> parts = split(text);
    bool ok = parts.size() == count;
    for (const std::string& part : parts) {
      double v = 0;
      ok = ok && read_number(part, v) == Reading::Ok;
    }
    return ok ? "" : "expects " + count_word(count) + " numbers " + form + found(text);
  });
}

CLI::Validator non_empty(const std::string& what) {
  return validator([what](std::string& text) -> std::string { return text.empty() ? "expects " + what + found(text) : ""; });
}

CLI::Validator path_name() { return non_empty("a file name"); }

std::vector<double> split_numbers(const std::string& text) {
  std::vector<double> out;
  for (const std::string& part : split(text)) {
    double v = 0;
    read_number(part, v);
    out.push_back(v);
  }
  return out;
}

}  // namespace cdp::app
