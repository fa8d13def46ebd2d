// The operator catalogue: every operator's parameters with ranges, defaults
// and meanings, and the kernel that runs it.
#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "kernels.h"
#include "relief/process/operators.h"
#include "relief/process/window_stats.h"

namespace relief::process {
namespace {

constexpr auto kLength = Scaling::Length;
const ParamSpec kRadius{
    "radius", 1, 9, 1, true, "window radius in samples: (2r+1)^2 masks up to 19 x 19", kLength};
const ParamSpec kLooks{"looks", 1, 100, 1, false, "equivalent number of looks L (Cu^2 = 1/L)"};
const ParamSpec kDeramp{"deramp", 0, 10, 0.1, false, "damping factor of the exponential kernel"};
const ParamSpec kSigma{"sigma", 0, 10, 0, false, "standard deviation in samples (0: radius / 2.5)",
                       kLength};
const ParamSpec kLevels{
    "levels", 1, 3, 2, true, "wavelet scales (margin 2 (2^levels - 1))", Scaling::DyadicScales};
const ParamSpec kThresholdK{"k", 0, 5, 1, false, "threshold in noise deviations of each band"};

const ParamSpec kSigmas{"sigmas", 0.5, 10, 3, false, "t = mean + sigmas * std (the seed's 3)"};
const ParamSpec kLogC{"c", 1, 1e6, 100, false, "brightness: g = log(1 + c a') / log(1 + c)"};
const ParamSpec kTMin{"t_min", -1e30, 1e30,
                      NAN,     false, "amplitude mapped to black (auto: global min)"};
const ParamSpec kTMax{"t_max", -1e30, 1e30,
                      NAN,     false, "amplitude mapped to white (auto: mean + 3 std)"};
const ParamSpec kGamma{"gamma", 0.05, 1, 0.5, false, "exponent applied to a / global max"};
const ParamSpec kRatGamma{"gamma", 0.05, 1, 0.7, false, "exponent applied to the amplitude"};
const ParamSpec kRatScale{"scale", 0.5, 10, 2.5, false, "white = scale * mean of a^gamma"};

const ParamSpec kDragoC{"c", 1, 1e6, 100, false, "as the logarithmic mapping's c"};
const ParamSpec kDragoM{"m",      1,     10,
                        2.302585, false, "maximum brightness (ln 10: the maximum is white)"};
const ParamSpec kDragoB{"b",    0,     1,
                        0.2345, false, "contrast: exponent of the adaptive base (bias 0.85)"};
const ParamSpec kTumblinC{"c", 1, 1e6, 100, false, "prescale of a in [0, 1] to cd/m^2"};
const ParamSpec kTumblinAd{"ad", 1, 1000, 50, false, "display adaptation luminance, cd/m^2"};
const ParamSpec kTumblinAa{"aa", 1e-6, 1e6, NAN, false, "amplitude adaptation (auto: c * mean)"};
const ParamSpec kSchlickB{"b", 1, 1e9, NAN, false, "brightness (auto: the mean maps to mid-grey)"};
const ParamSpec kRdB{"b", -8, 8, 0, false, "brightness"};
const ParamSpec kRdC{"c", 0, 1, 0, false, "contrast: weight of the global average in l"};

const ParamSpec kMaxRadius{
    "max_radius", 1, 10, 10, true, "largest Gauss radius of the local averages (sigma = r / 2.5)",
    kLength};
const ParamSpec kAdaptivity{"d", 0, 1, 0.5, false, "adaptivity: 0 is the global method"};
const ParamSpec kQuotient{"t", 0, 10, 0.2, false, "quotient threshold |G_r - G_r+1| / G_r"};
const ParamSpec kChiuC{"c", 0.01, 100, 2, false, "g = a / (c G_r)"};
const ParamSpec kChiuRadius{"radius", 1, 10, 10, true, "Gauss radius (sigma = r / 2.5)", kLength};
const ParamSpec kRetinexP{"p", 1, 1e6, 100, false, "prescale inside log(1 + p a)"};
const ParamSpec kRetinexW{"w", 0.1, 10, 1, false, "weights w^0, w^1, w^2 of the three scales"};
const ParamSpec kRetinexRange{"range", 0.1, 10, 2, false, "log ratio mapped to white"};
const ParamSpec kAshC{"c", 1, 1e6, 100, false, "prescale of a in [0, 1] to cd/m^2"};
const ParamSpec kAshT{"t", 0.01, 1, 0.5, false, "gradient threshold the averages may not cross"};
const ParamSpec kReinhardC{"c", 1e-3, 1e6, NAN, false, "key: prescale (auto: 0.18 / mean)"};
const ParamSpec kReinhardW{"w", 1e-3, 1e6, NAN, false, "prescaled value mapped to white (auto: c)"};
const ParamSpec kReinhardS{"s", 1, 20, 8, false, "sharpness phi"};
const ParamSpec kReinhardT{"t", 1e-3, 1, 0.05, false, "scale-selection threshold epsilon"};
const ParamSpec kDurandRadius{
    "radius", 1, 10, 5, true, "bilateral spatial radius (sigma = r / 2.5)", kLength};
const ParamSpec kDurandSigmaR{"sigma_r", 0.05, 5, 0.4, false, "range sigma in log10 units"};
const ParamSpec kDurandK{"k", 0.05, 1, 0.35, false, "compression of the base layer"};

constexpr const char* kAmplitude = "SAR amplitude, linear";

struct Entry {
  OperatorSpec spec;
  Kernel kernel;
};

// Operator flags: {needs_global_stats, sar_only}.
OperatorSpec filter(const char* name, const char* summary, const char* input,
                    std::vector<ParamSpec> params, bool sar_only) {
  return {name, summary, input, std::move(params), false, sar_only};
}
OperatorSpec mapping(const char* name, const char* summary, std::vector<ParamSpec> params) {
  return {name, summary, kAmplitude, std::move(params), true, true};
}

const std::vector<Entry>& entries() {
  static const std::vector<Entry> list = {
      // Speckle filters (seed 003 §2.3).
      {filter("mean", "mean of the window", "any", {kRadius}, false), mean_kernel},
      {filter("gauss", "Gaussian smoothing (separable)", "any", {kRadius, kSigma}, false),
       gauss_kernel},
      {filter("median", "median of the window; separable approximation above radius 3", "any",
              {kRadius}, false),
       median_kernel},
      {filter("lee", "Lee MMSE speckle filter", kAmplitude, {kRadius, kLooks}, true), lee_kernel},
      {filter("kuan", "Kuan speckle filter", kAmplitude, {kRadius, kLooks}, true), kuan_kernel},
      {filter("frost", "Frost speckle filter (exponential kernel)", kAmplitude, {kRadius, kDeramp},
              true),
       frost_kernel},
      {filter("gamma-map", "Gamma maximum a posteriori speckle filter", kAmplitude,
              {kRadius, kLooks}, true),
       gamma_map_filter_kernel},
      {filter("wavelet", "a trous wavelet soft thresholding of log amplitudes", kAmplitude,
              {kLevels, kThresholdK, kLooks}, true),
       wavelet_kernel},
      // Global dynamic-range reduction (§2.2.3, §2.2.4).
      {mapping("linear", "linear mapping a / (mean + 3 std), clipped", {kSigmas}), linear_kernel},
      {mapping("log", "logarithmic mapping of [t_min, t_max]", {kLogC, kTMin, kTMax}), log_kernel},
      {mapping("gamma", "gamma mapping (a / max)^gamma", {kGamma}), gamma_kernel},
      {mapping("rat", "RAT: a^gamma, then [0, scale * mean] to [0, 1]", {kRatGamma, kRatScale}),
       rat_kernel},
      {mapping("drago", "Drago adaptive logarithmic mapping", {kDragoC, kDragoM, kDragoB}),
       drago_kernel},
      {mapping("tumblin", "Tumblin-Rushmeier brightness-preserving operator",
               {kTumblinC, kTumblinAd, kTumblinAa}),
       tumblin_kernel},
      {mapping("schlick", "Schlick uniform rational quantization", {kSchlickB}), schlick_kernel},
      {mapping("reinhard-devlin", "Reinhard-Devlin photoreceptor model", {kRdB, kRdC}),
       reinhard_devlin_kernel},
      // Local dynamic-range reduction (§2.2.4, §2.2.5).
      {mapping("chiu", "Chiu spatially variant operator a / (c G_r)", {kChiuC, kChiuRadius}),
       chiu_kernel},
      {mapping("retinex", "Rahman-Jobson-Woodell multiscale retinex",
               {kRetinexP, kRetinexW, kRetinexRange, kMaxRadius}),
       retinex_kernel},
      {mapping("ashikhmin", "Ashikhmin spatially variant operator", {kAshC, kAshT, kMaxRadius}),
       ashikhmin_kernel},
      {mapping("reinhard", "Reinhard photographic tone reproduction (dodging and burning)",
               {kReinhardC, kReinhardW, kReinhardS, kReinhardT, kMaxRadius}),
       reinhard_kernel},
      {mapping("durand", "Durand-Dorsey bilateral base/detail compression",
               {kDurandRadius, kDurandSigmaR, kDurandK}),
       durand_kernel},
      {mapping("ext-schlick", "Schlick with the SAR adaptation value (seed 003 §2.2.5)",
               {kSchlickB, kAdaptivity, kQuotient, kMaxRadius}),
       ext_schlick_kernel},
      {mapping("ext-reinhard-devlin", "Reinhard-Devlin with the SAR adaptation value",
               {kRdB, kRdC, kAdaptivity, kQuotient, kMaxRadius}),
       ext_reinhard_devlin_kernel},
      // Explicit conversions.
      {filter("intensity-to-amplitude", "A = sqrt(I)", "SAR intensity, linear", {}, true),
       intensity_to_amplitude_kernel},
      {filter("amplitude-to-intensity", "I = A^2", kAmplitude, {}, true),
       amplitude_to_intensity_kernel},
      {filter("db-to-amplitude", "A = 10^(dB / 20) (= sqrt of 10^(dB / 10) intensity)", "SAR in dB",
              {}, true),
       db_to_amplitude_kernel},
      {filter("amplitude-to-db", "dB = 20 log10(A); A <= 0 becomes nodata", kAmplitude, {}, true),
       amplitude_to_db_kernel},
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

int margin_of(const OperatorSpec& op, const Params& params) {
  if (op.name == "wavelet")
    return params.at("levels") > 0 ? wavelet_margin(static_cast<int>(params.at("levels"))) : 0;
  int margin = 0;
  for (const auto& spec : op.params) {
    if (spec.scaling == Scaling::Length && spec.integer) {
      margin = std::max(margin, static_cast<int>(params.at(spec.name)));
    }
  }
  return margin;
}

Params scale_params(const OperatorSpec& op, const Params& params, double factor) {
  assert(factor >= 1);
  Params scaled = params;
  for (const auto& spec : op.params) {
    double& v = scaled.at(spec.name);
    if (spec.scaling == Scaling::Length) {
      v = spec.integer ? std::round(v / factor) : v / factor;
    } else if (spec.scaling == Scaling::DyadicScales) {
      v = std::max(0.0, v - std::round(std::log2(factor)));
    }
  }
  return scaled;
}

Status run_operator(const OperatorSpec& op, const Params& params, ConstView input, MutView output,
                    Executor& executor, const GlobalStats* stats,
                    std::optional<bool> small_integers) {
  const Entry* e = find_entry(op.name);
  assert(e);
  const int m = margin_of(op, params);
  if (input.width != output.width + 2 * m || input.height != output.height + 2 * m) {
    return fail(fmt::format("{}: input must extend {} samples beyond the output", op.name, m));
  }
  KernelContext context{params, {}, false};
  if (op.needs_global_stats) {
    if (!stats) return fail(fmt::format("{}: needs the dataset's global statistics", op.name));
    if (!(stats->max > stats->min) || !(stats->stddev > 0) || !(stats->max > 0)) {
      return fail(
          fmt::format("{}: the data has no dynamic range to reduce (constant, not positive or no "
                      "valid samples)",
                      op.name));
    }
    context.stats = *stats;
    if (op.name == "log") {
      const double t_min = std::isnan(params.at("t_min")) ? stats->min : params.at("t_min");
      const double t_max =
          std::isnan(params.at("t_max")) ? stats->mean + 3 * stats->stddev : params.at("t_max");
      if (!(t_max > t_min)) {
        return fail(
            fmt::format("--param: t_max ({}) must be greater than t_min ({})", t_max, t_min));
      }
    }
  }
  // Wavelet with no scale left (a coarse pyramid level) and radius-0 masks
  // other than the local mappings' reduce to the sample itself.
  if (op.name == "wavelet" && params.at("levels") == 0) {
    for (int y = 0; y < output.height; ++y) {
      std::copy_n(input.row(y), output.width, output.row(y));
    }
    return {};
  }
  // Mean, Lee and Kuan sum exactly whatever the values (window_stats.h).
  const bool exact_sums = op.name == "mean" || op.name == "lee" || op.name == "kuan";
  if (m > 0 && !exact_sums) {
    context.integral_input = small_integers ? *small_integers : all_small_integers(input);
  }
  constexpr int kRowsPerTask = 32;
  const int tasks = (output.height + kRowsPerTask - 1) / kRowsPerTask;
  executor.parallel_for(static_cast<size_t>(tasks), [&](size_t t) {
    const int y0 = static_cast<int>(t) * kRowsPerTask;
    e->kernel(input, output, context, y0, std::min(output.height, y0 + kRowsPerTask));
  });
  return {};
}

}  // namespace relief::process
