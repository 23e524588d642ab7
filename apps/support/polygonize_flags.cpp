#include "polygonize_flags.h"

#include "command_line.h"

namespace cdp::app {

PolygonizeFlags::PolygonizeFlags(CLI::App& app) {
  CLI::Option_group* adaptive = app.add_option_group("adaptive method");
  CLI::Option_group* marching = app.add_option_group("mc and mt methods");
  std::vector<std::pair<std::string_view, CLI::Option*>> exclusive;  // (group, option) so far
  for (const OptionSpec& spec : polygonize_options()) {
    CLI::App* to = spec.methods == OptionMethods::All        ? &app
                   : spec.methods == OptionMethods::Adaptive ? static_cast<CLI::App*>(adaptive)
                                                             : static_cast<CLI::App*>(marching);
    const std::string flag = option_flag(spec), help(spec.help);
    CLI::Option* o = nullptr;
    switch (spec.kind) {
      case OptionKind::Number:
        o = to->add_option(flag, numbers_.emplace_back(0), help)->transform(positive_number());
        break;
      case OptionKind::Real:
        o = to->add_option(flag, numbers_.emplace_back(0), help)->transform(number());
        break;
      case OptionKind::Integer:
        o = to->add_option(flag, integers_.emplace_back(0), help)->transform(integer_in(spec.lo, spec.hi));
        break;
      case OptionKind::Choice: {
        std::vector<std::string> accepted(spec.choices.begin(), spec.choices.end());
        for (const auto& [alias, meaning] : spec.aliases) accepted.emplace_back(alias);
        o = to->add_option(flag, texts_.emplace_back(), help)->check(CLI::IsMember(accepted));
        break;
      }
      case OptionKind::Flag:
        o = to->add_flag(flag, flags_.emplace_back(false), help);
        break;
      case OptionKind::Boolean:
        o = to->add_option(flag, texts_.emplace_back(), help)->check(CLI::IsMember({"true", "false"}));
        break;
    }
    if (!spec.value_name.empty()) o->type_name(std::string(spec.value_name));
    if (!spec.default_text.empty() && spec.kind != OptionKind::Flag) o->default_str(std::string(spec.default_text));
    if (!spec.exclusive.empty()) {
      for (const auto& [group, earlier] : exclusive)
        if (group == spec.exclusive) o->excludes(earlier);
      exclusive.emplace_back(spec.exclusive, o);
    }
    entries_.push_back({&spec, o});
  }
}

nlohmann::json PolygonizeFlags::given() const {
  nlohmann::json j = nlohmann::json::object();
  for (const Entry& e : entries_) {
    if (e.option->count() == 0) continue;
    const OptionSpec& spec = *e.spec;
    const std::string name(spec.name);
    switch (spec.kind) {
      case OptionKind::Number:
      case OptionKind::Real: j[name] = e.option->as<double>(); break;
      case OptionKind::Integer: j[name] = e.option->as<long long>(); break;
      case OptionKind::Choice: j[name] = e.option->as<std::string>(); break;
      case OptionKind::Flag: j[name] = true; break;
      case OptionKind::Boolean: j[name] = e.option->as<std::string>() == "true"; break;
    }
  }
  return j;
}

std::string PolygonizeFlags::not_applying(const std::string& method) const {
  for (const Entry& e : entries_)
    if (e.option->count() > 0 && !applies_to(*e.spec, method))
      return e.option->get_name();
  return "";
}

}  // namespace cdp::app
