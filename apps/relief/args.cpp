#include "args.h"

#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "relief/base/memory_use.h"
#include "relief/base/units.h"

namespace relief::cli {

Result<Args> Args::parse(const std::vector<std::string>& argv, const std::vector<OptionSpec>& specs,
                         const std::string& command) {
  Args args;
  for (size_t i = 0; i < argv.size(); ++i) {
    std::string arg = argv[i];
    if (arg.size() < 2 || arg[0] != '-' || arg == "--") {
      args.positional_.push_back(arg);
      continue;
    }
    std::optional<std::string> inline_value;
    if (auto eq = arg.find('='); eq != std::string::npos && arg.starts_with("--")) {
      inline_value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
    }
    const OptionSpec* spec = nullptr;
    for (const auto& s : specs) {
      if (arg == s.name || (!s.alias.empty() && arg == s.alias)) spec = &s;
    }
    if (!spec)
      return fail(
          fmt::format("{}: unknown option '{}' (see relief {} --help)", command, arg, command));
    if (!spec->takes_value) {
      if (inline_value)
        return fail(fmt::format("{}: option {} takes no value", command, spec->name));
      args.values_[spec->name] = "";
      continue;
    }
    if (inline_value) {
      args.values_[spec->name] = *inline_value;
    } else if (i + 1 < argv.size()) {
      args.values_[spec->name] = argv[++i];
    } else {
      return fail(fmt::format("{}: option {} needs a value", command, spec->name));
    }
    args.all_values_[spec->name].push_back(args.values_[spec->name]);
  }
  return args;
}

std::optional<std::string> Args::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::vector<std::string> Args::get_all(const std::string& name) const {
  auto it = all_values_.find(name);
  return it == all_values_.end() ? std::vector<std::string>{} : it->second;
}

Result<std::optional<int>> Args::get_int(const std::string& name, int lo, int hi) const {
  auto v = get(name);
  if (!v) return std::optional<int>();
  int value = 0;
  auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), value);
  if (ec != std::errc() || p != v->data() + v->size()) {
    return fail(fmt::format("{}: '{}' is not an integer", name, *v));
  }
  if (value < lo || value > hi)
    return fail(fmt::format("{}: {} is not in {}..{}", name, value, lo, hi));
  return std::optional<int>(value);
}

Result<std::pair<int, int>> parse_int_pair(const std::string& option, const std::string& text,
                                           char separator, int lo, int hi, std::string_view form) {
  const auto number = [&](std::string_view digits) -> std::optional<int> {
    int value = 0;
    if (digits.empty() || digits.front() < '0' || digits.front() > '9') return std::nullopt;
    const auto [p, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec != std::errc() || p != digits.data() + digits.size()) return std::nullopt;  // overflow
    if (value < lo || value > hi) return std::nullopt;
    return value;
  };
  const auto at = text.find(separator);
  const auto first = number(std::string_view(text).substr(0, at));
  const auto second =
      at == std::string::npos ? std::nullopt : number(std::string_view(text).substr(at + 1));
  if (!first || !second) return fail(fmt::format("{}: '{}' is not {}", option, text, form));
  return std::pair{*first, *second};
}

Result<WidthHeight> parse_width_height(const std::string& option, const std::string& text,
                                       int max) {
  const auto [width, height] = RELIEF_TRY(parse_int_pair(
      option, text, 'x', 1, max, fmt::format("WxH between 1x1 and {}x{}", max, max)));
  return WidthHeight{width, height};
}

Result<std::optional<double>> Args::get_double(const std::string& name) const {
  auto v = get(name);
  if (!v) return std::optional<double>();
  double value = 0;
  auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), value);
  if (ec != std::errc() || p != v->data() + v->size() || !std::isfinite(value)) {
    return fail(fmt::format("{}: '{}' is not a number", name, *v));
  }
  return std::optional<double>(value);
}

Result<std::vector<double>> parse_numbers(const std::string& option, const std::string& text,
                                          size_t count) {
  std::vector<double> out;
  size_t start = 0;
  for (;;) {
    const size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? comma : comma - start);
    double v = 0;
    auto [ptr, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || ec != std::errc() || ptr != item.data() + item.size() ||
        !std::isfinite(v)) {
      return fail(fmt::format("{}: '{}' is not a number", option, item));
    }
    out.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (count && out.size() != count) {
    return fail(fmt::format("{}: expected {} comma-separated numbers", option, count));
  }
  return out;
}

Result<uint64_t> parse_memory_budget(const std::string& text, uint64_t minimum) {
  auto bytes = parse_byte_size(text);
  if (!bytes) return fail("--memory: " + bytes.error().message);
  if (*bytes < minimum) {
    return fail(fmt::format("--memory: {} is below the least this command needs ({})", text,
                            format_bytes(minimum)));
  }
  if (const uint64_t physical = physical_memory_bytes(); physical && *bytes > physical) {
    return fail(fmt::format("--memory: {} is more than this machine's memory ({})", text,
                            format_bytes(physical)));
  }
  return *bytes;
}

}  // namespace relief::cli
