#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "relief/process/operators.h"
#include "relief/process/speckle.h"
#include "relief/process/window_stats.h"

namespace relief::process {
namespace {

const ParamSpec kRadius{"radius", 1,    9,
                        1,        true, "window radius in samples: (2r+1)^2 masks up to 19 x 19"};
const ParamSpec kLooks{"looks", 1, 100, 1, false, "equivalent number of looks L (Cu^2 = 1/L)"};
const ParamSpec kDeramp{"deramp", 0, 10, 0.1, false, "damping factor of the exponential kernel"};
const ParamSpec kSigma{"sigma", 0, 10, 0, false, "standard deviation in samples (0: radius / 2.5)"};

const ParamSpec kSigmas{"sigmas", 0.5, 10, 3, false, "t = mean + sigmas * std (the seed's 3)"};
const ParamSpec kLogC{"c", 1, 1e6, 100, false, "brightness: g = log(1 + c a') / log(1 + c)"};
const ParamSpec kTMin{"t_min", -1e30, 1e30,
                      NAN,     false, "amplitude mapped to black (default: global min)"};
const ParamSpec kTMax{"t_max", -1e30, 1e30,
                      NAN,     false, "amplitude mapped to white (default: mean + 3 std)"};
const ParamSpec kGamma{"gamma", 0.05, 1, 0.5, false, "exponent applied to a / global max"};

using Filter = void (*)(ConstView, MutView, const SpeckleParams&, int, int);
using PointOperator = void (*)(ConstView, MutView, const Params&, const GlobalStats&, int, int);

void run_linear(ConstView in, MutView out, const Params& p, const GlobalStats& g, int y0, int y1) {
  linear_map(in, out, g.mean + p.at("sigmas") * g.stddev, y0, y1);
}
void run_log(ConstView in, MutView out, const Params& p, const GlobalStats& g, int y0, int y1) {
  const double t_min = std::isnan(p.at("t_min")) ? g.min : p.at("t_min");
  const double t_max = std::isnan(p.at("t_max")) ? g.mean + 3 * g.stddev : p.at("t_max");
  log_map(in, out, p.at("c"), t_min, t_max, y0, y1);
}
void run_gamma(ConstView in, MutView out, const Params& p, const GlobalStats& g, int y0, int y1) {
  gamma_map(in, out, p.at("gamma"), g.max, y0, y1);
}

struct Entry {
  OperatorSpec spec;
  Filter filter = nullptr;
  PointOperator point = nullptr;
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> list = {
      {{"mean", "mean of the window", "any", {kRadius}}, mean_filter},
      {{"gauss", "Gaussian smoothing (separable)", "any", {kRadius, kSigma}}, gauss_filter},
      {{"median", "median of the window; separable approximation above radius 3", "any", {kRadius}},
       median_filter},
      {{"lee", "Lee MMSE speckle filter", "SAR amplitude, linear", {kRadius, kLooks}}, lee_filter},
      {{"kuan", "Kuan speckle filter", "SAR amplitude, linear", {kRadius, kLooks}}, kuan_filter},
      {{"frost",
        "Frost speckle filter (exponential kernel)",
        "SAR amplitude, linear",
        {kRadius, kDeramp}},
       frost_filter},
      {{"gamma-map",
        "Gamma maximum a posteriori speckle filter",
        "SAR amplitude, linear",
        {kRadius, kLooks}},
       gamma_map_filter},
      {{"linear",
        "linear mapping a / (mean + 3 std), clipped",
        "SAR amplitude, linear",
        {kSigmas},
        true},
       nullptr,
       run_linear},
      {{"log",
        "logarithmic mapping of [t_min, t_max]",
        "SAR amplitude, linear",
        {kLogC, kTMin, kTMax},
        true},
       nullptr,
       run_log},
      {{"gamma", "gamma mapping (a / max)^gamma", "SAR amplitude, linear", {kGamma}, true},
       nullptr,
       run_gamma},
  };
  return list;
}

const Entry* find_entry(const std::string& name) {
  for (const auto& e : entries()) {
    if (e.spec.name == name) return &e;
  }
  return nullptr;
}

}  // namespace

const std::vector<OperatorSpec>& operator_catalogue() {
  static const std::vector<OperatorSpec> specs = [] {
    std::vector<OperatorSpec> s;
    for (const auto& e : entries()) s.push_back(e.spec);
    return s;
  }();
  return specs;
}

const OperatorSpec* find_operator(const std::string& name) {
  const Entry* e = find_entry(name);
  return e ? &e->spec : nullptr;
}

Result<Params> parse_params(const OperatorSpec& op, const std::vector<std::string>& assignments) {
  Params params;
  for (const auto& p : op.params) params[p.name] = p.default_value;
  for (const auto& a : assignments) {
    const auto eq = a.find('=');
    if (eq == std::string::npos) {
      return fail(fmt::format("--param: '{}' is not key=value", a));
    }
    const std::string key = a.substr(0, eq), text = a.substr(eq + 1);
    auto spec = std::find_if(op.params.begin(), op.params.end(),
                             [&](const ParamSpec& p) { return p.name == key; });
    if (spec == op.params.end()) {
      return fail(fmt::format("--param: operator {} has no parameter '{}'", op.name, key));
    }
    double value = 0;
    auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value)) {
      return fail(fmt::format("--param: {}='{}' is not a number", key, text));
    }
    if (spec->integer && value != std::floor(value)) {
      return fail(fmt::format("--param: {}={} must be a whole number", key, text));
    }
    if (value < spec->min || value > spec->max) {
      return fail(
          fmt::format("--param: {}={} is out of range [{}, {}]", key, text, spec->min, spec->max));
    }
    params[key] = value;
  }
  return params;
}

int margin_of(const OperatorSpec&, const Params& params) {
  auto it = params.find("radius");
  return it == params.end() ? 0 : static_cast<int>(it->second);
}

Status run_operator(const OperatorSpec& op, const Params& params, ConstView input, MutView output,
                    Executor& executor, const GlobalStats* stats) {
  const Entry* e = find_entry(op.name);
  assert(e);
  const int m = margin_of(op, params);
  if (input.width != output.width + 2 * m || input.height != output.height + 2 * m) {
    return fail(fmt::format("{}: input must extend {} samples beyond the output", op.name, m));
  }
  constexpr int kRowsPerTask = 32;
  const int tasks = (output.height + kRowsPerTask - 1) / kRowsPerTask;
  if (e->point) {
    if (!stats) return fail(fmt::format("{}: needs the dataset's global statistics", op.name));
    if (!(stats->max > stats->min) || !(stats->stddev > 0)) {
      return fail(fmt::format(
          "{}: the data has no dynamic range to reduce (constant or no valid samples)", op.name));
    }
    const double t_min =
        params.count("t_min") && !std::isnan(params.at("t_min")) ? params.at("t_min") : stats->min;
    const double t_max = params.count("t_max") && !std::isnan(params.at("t_max"))
                             ? params.at("t_max")
                             : stats->mean + 3 * stats->stddev;
    if (op.name == "log" && !(t_max > t_min)) {
      return fail(fmt::format("--param: t_max ({}) must be greater than t_min ({})", t_max, t_min));
    }
    executor.parallel_for(static_cast<size_t>(tasks), [&](size_t t) {
      const int y0 = static_cast<int>(t) * kRowsPerTask;
      e->point(input, output, params, *stats, y0, std::min(output.height, y0 + kRowsPerTask));
    });
    return {};
  }
  SpeckleParams sp;
  sp.radius = m;
  if (auto it = params.find("looks"); it != params.end()) sp.looks = it->second;
  if (auto it = params.find("deramp"); it != params.end()) sp.deramp = it->second;
  if (auto it = params.find("sigma"); it != params.end()) sp.sigma = it->second;
  sp.integral_input = all_small_integers(input);
  executor.parallel_for(static_cast<size_t>(tasks), [&](size_t t) {
    const int y0 = static_cast<int>(t) * kRowsPerTask;
    e->filter(input, output, sp, y0, std::min(output.height, y0 + kRowsPerTask));
  });
  return {};
}

}  // namespace relief::process
