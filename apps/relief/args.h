#pragma once
// A small command-line parser: each command declares its options; anything
// else is a one-line error naming the argument.
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "relief/base/result.h"

namespace relief::cli {

struct OptionSpec {
  OptionSpec(std::string n, std::string a = "", bool value = true)
      : name(std::move(n)), alias(std::move(a)), takes_value(value) {}
  std::string name;   // "--output"
  std::string alias;  // "-o" or ""
  bool takes_value;
};

class Args {
 public:
  static Result<Args> parse(const std::vector<std::string>& argv,
                            const std::vector<OptionSpec>& specs, const std::string& command);

  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::optional<std::string> get(const std::string& name) const;  // the last one given
  // Every value of an option given several times, in the order given.
  std::vector<std::string> get_all(const std::string& name) const;

  Result<std::optional<int>> get_int(const std::string& name, int lo, int hi) const;
  Result<std::optional<double>> get_double(const std::string& name) const;

 private:
  std::map<std::string, std::string> values_;
  std::map<std::string, std::vector<std::string>> all_values_;
  std::vector<std::string> positional_;
};

// Two integers in lo..hi joined by `separator` ("1280x720", "3/8", "10,20"):
// decimal digits only (no sign, no space) and no wrap-around (4294967297 is
// out of range, not 1). The error names `option` and says `form`.
Result<std::pair<int, int>> parse_int_pair(const std::string& option, const std::string& text,
                                           char separator, int lo, int hi, std::string_view form);

// "WxH" with both sides in 1..`max`.
struct WidthHeight {
  int width = 0;
  int height = 0;
};
Result<WidthHeight> parse_width_height(const std::string& option, const std::string& text, int max);

// "1,2.5,-3" as numbers; `count` > 0 requires exactly that many. Errors name `option`.
Result<std::vector<double>> parse_numbers(const std::string& option, const std::string& text,
                                          size_t count = 0);

// A --memory budget ("256MiB", "2GiB"): at least `minimum` bytes and no more
// than the machine has (a budget the machine cannot give would only move
// the failure to an out-of-memory kill late in the work).
Result<uint64_t> parse_memory_budget(const std::string& text, uint64_t minimum);

}  // namespace relief::cli
