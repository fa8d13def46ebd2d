#pragma once
// The operator catalogue: names, parameters with ranges and defaults, and what
// each expects as input. `relief process --list` prints it.
#include <map>
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/result.h"
#include "relief/process/dynamic_range.h"
#include "relief/process/view.h"

namespace relief::process {

struct ParamSpec {
  std::string name;
  double min, max, default_value;  // a NaN default is derived from the global statistics
  bool integer;
  std::string meaning;
};

struct OperatorSpec {
  std::string name;
  std::string summary;
  std::string input;  // what the operator expects ("amplitude, linear", ...)
  std::vector<ParamSpec> params;
  bool needs_global_stats = false;  // global dynamic-range operators
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

// Runs the operator: `input` extends margin_of() samples beyond `output` on
// every side. NaN is nodata in and out. Rows are spread over the executor.
// `stats` are the dataset's global statistics; operators that need them fail
// without them.
Status run_operator(const OperatorSpec& op, const Params& params, ConstView input, MutView output,
                    Executor& executor, const GlobalStats* stats = nullptr);

}  // namespace relief::process
