#pragma once
// The operator catalogue: names, parameters with ranges and defaults, and what
// each expects as input. `relief process --list` prints it.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/result.h"
#include "relief/process/dynamic_range.h"
#include "relief/process/view.h"

namespace relief::process {

// How a parameter follows the pyramid level so that masks keep their size in
// world space (seed 003 §2.3.3): a length in samples halves with each coarser
// level; a number of dyadic scales loses one.
enum class Scaling { None, Length, DyadicScales };

struct ParamSpec {
  std::string name;
  double min, max, default_value;  // a NaN default is derived from the global statistics
  bool integer;
  std::string meaning;
  Scaling scaling = Scaling::None;
};

struct OperatorSpec {
  std::string name;
  std::string summary;
  std::string input;  // what the operator expects ("amplitude, linear", ...)
  std::vector<ParamSpec> params;
  bool needs_global_stats = false;  // dynamic-range operators
  bool sar_only = false;            // meaningless on elevation or imagery
};

const std::vector<OperatorSpec>& operator_catalogue();
const OperatorSpec* find_operator(const std::string& name);

// Parameters after validation: every parameter of the operator, defaults filled in.
using Params = std::map<std::string, double>;
// Parses "key=value" strings against the operator's specs; unknown keys and
// out-of-range values are errors naming the parameter.
Result<Params> parse_params(const OperatorSpec& op, const std::vector<std::string>& assignments);

// The number of input samples an operator needs beyond each side of its output.
int margin_of(const OperatorSpec& op, const Params& params);

// The parameters for data `factor` (a power of two >= 1) times coarser than
// the data they were given for: lengths divided, rounded, possibly to 0 (a
// mask smaller than one sample: the operator then uses the sample itself).
Params scale_params(const OperatorSpec& op, const Params& params, double factor);

// Runs the operator: `input` extends margin_of() samples beyond `output` on
// every side. NaN is nodata in and out. Rows are spread over the executor.
// `stats` are the dataset's global statistics; operators that need them fail
// without them. `small_integers` says whether every valid input is an integer
// of magnitude <= 2^20 when the caller knows (an 8- or 16-bit source);
// otherwise the input is scanned (window_stats.h).
Status run_operator(const OperatorSpec& op, const Params& params, ConstView input, MutView output,
                    Executor& executor, const GlobalStats* stats = nullptr,
                    std::optional<bool> small_integers = std::nullopt);

}  // namespace relief::process
