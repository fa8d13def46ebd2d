#include "operator_shaders.h"

#include <algorithm>
#include <cmath>

namespace relief::gpuprocess {
namespace {

const ShaderBodies& bodies() {
  static const ShaderBodies map = [] {
    ShaderBodies b;
    add_point_shaders(b);
    add_speckle_shaders(b);
    add_local_mapping_shaders(b);
    return b;
  }();
  return map;
}

std::vector<double> gauss_weights(int radius, double sigma) {
  std::vector<double> kernel;
  for (int d = -radius; d <= radius; ++d)
    kernel.push_back(std::exp(-0.5 * d * d / (sigma * sigma)));
  return kernel;
}

// These mirror libs/process/src/tone_mapping_global.cpp (private there); the
// GPU = CPU tests catch any drift.
double auto_schlick_b(const process::GlobalStats& g) {
  const double m = g.mean / g.max;
  return std::max(1.0, (1 - m) / m);
}
double reinhard_devlin_exponent(const process::GlobalStats& g) {
  const double avg = g.mean / g.max, lo = std::max(0.0, g.min) / g.max;
  return 0.3 + 0.7 * std::pow((1 - avg) / (1 - lo), 1.4);
}
double capacity(double l) {
  if (l < 0.0034) return l / 0.0014;
  if (l < 1) return 2.4483 + std::log10(l / 0.0034) / 0.4027;
  if (l < 7.2444) return 16.5630 + (l - 1) / 0.4027;
  return 32.0693 + std::log10(l / 7.2444) / 0.0556;
}
double tumblin_gamma(double luminance) {
  return luminance > 100 ? 2.655 : 1.855 + 0.4 * std::log10(luminance + 2.3e-5);
}

}  // namespace

std::string operator_shader(const std::string& name, int radius) {
  auto it = bodies().find(name);
  if (it == bodies().end()) return {};
  // Window-rows operators have their own main() (runs of outputs).
  const std::string main = uses_window_rows(name) ? std::string() : shader_main();
  std::string t = shader_frame() + shader_math() + main + it->second;
  if (radius >= 0) {
    with_radius(t, radius);
    with_runs(t, radius);
  }
  return t;
}

void with_radius(std::string& source, int radius) {
  const std::string uniform = "uniform int r;";
  const size_t at = source.find(uniform);
  assert(at != std::string::npos);
  source.replace(at, uniform.size(), "const int r = " + std::to_string(radius) + ";");
}

StepUniforms step_uniforms(const ChainStep& step, const process::GlobalStats& g) {
  StepUniforms u;
  const auto p = [&](const char* key) { return step.params.at(key); };
  const auto has = [&](const char* key) { return step.params.contains(key); };
  const std::string& name = step.op->name;
  if (has("radius")) u.r = static_cast<int>(p("radius"));
  if (has("max_radius")) u.r = static_cast<int>(p("max_radius"));
  auto& k = u.k;
  if (name == "lee" || name == "kuan") {
    k[0] = 1.0 / p("looks");
  } else if (name == "gamma-map") {
    k[0] = p("looks"), k[1] = 1.0 / k[0], k[2] = std::sqrt(2.0) * std::sqrt(k[1]);
  } else if (name == "frost") {
    k[0] = p("deramp");
  } else if (name == "gauss") {
    const double sigma = p("sigma") > 0 ? p("sigma") : (u.r > 0 ? u.r / 2.5 : 1.0);
    u.w = gauss_weights(u.r, sigma);
  } else if (name == "linear") {
    k[0] = g.mean + p("sigmas") * g.stddev;
  } else if (name == "log") {
    const double t_min = std::isnan(p("t_min")) ? g.min : p("t_min");
    const double t_max = std::isnan(p("t_max")) ? g.mean + 3 * g.stddev : p("t_max");
    k[0] = t_min, k[1] = t_max - t_min, k[2] = p("c"), k[3] = std::log1p(p("c"));
  } else if (name == "gamma") {
    k[0] = p("gamma"), k[1] = g.max;
  } else if (name == "rat") {
    k[0] = p("gamma"), k[1] = p("scale") * process::estimated_power_mean(g, p("gamma"));
  } else if (name == "drago") {
    k[0] = p("c"), k[1] = p("m") / std::log1p(p("c")), k[2] = p("b"), k[3] = 1 / g.max;
  } else if (name == "tumblin") {
    const double scale = 1 / g.max;
    const double aa = std::isnan(p("aa")) ? std::max(1e-6, p("c") * g.mean * scale) : p("aa");
    k[0] = p("ad") / 100, k[1] = p("c"), k[2] = scale, k[3] = aa;
    k[4] = tumblin_gamma(aa) / tumblin_gamma(p("ad"));
  } else if (name == "schlick" || name == "ext-schlick") {
    k[0] = std::isnan(p("b")) ? auto_schlick_b(g) : p("b"), k[1] = 1 / g.max;
    if (name == "ext-schlick") k[1] = p("d"), k[2] = p("t"), k[3] = 1 / g.max;
  } else if (name == "reinhard-devlin" || name == "ext-reinhard-devlin") {
    k[0] = reinhard_devlin_exponent(g), k[1] = std::exp(-p("b")), k[2] = p("c");
    k[3] = g.mean / g.max;
    if (name == "reinhard-devlin") {
      k[4] = 1 / g.max;
    } else {
      k[4] = p("d"), k[5] = p("t"), k[6] = 1 / g.max;
    }
  } else if (name == "durand") {
    const double sigma_s = u.r > 0 ? u.r / 2.5 : 1.0, sigma_r = p("sigma_r");
    k[0] = p("k"), k[1] = 1 / g.max, k[2] = sigma_r, k[3] = 4 * sigma_r / (4096 - 1);
    for (int dy = -u.r; dy <= u.r; ++dy) {
      for (int dx = -u.r; dx <= u.r; ++dx) {
        u.w.push_back(std::exp(-0.5 * (dx * dx + dy * dy) / (sigma_s * sigma_s)));
      }
    }
  } else if (name == "chiu") {
    k[0] = p("c"), k[1] = 1 / g.max;
  } else if (name == "retinex") {
    const int big = u.r;
    k[0] = p("p"), k[1] = p("w"), k[2] = p("range");
    k[3] = std::max(1, big / 5), k[4] = std::max(1, big / 2), k[5] = big, k[6] = 1 / g.max;
  } else if (name == "ashikhmin") {
    k[0] = p("c"), k[1] = p("t");
    k[2] = capacity(p("c") * std::max(0.0, g.min) / g.max), k[3] = capacity(p("c"));
    k[4] = 1 / g.max;
  } else if (name == "reinhard") {
    const double mean = g.mean / g.max;
    k[0] = std::isnan(p("c")) ? 0.18 / mean : p("c");
    k[1] = std::isnan(p("w")) ? k[0] : p("w");
    k[2] = std::pow(2.0, p("s")), k[3] = p("t"), k[4] = 1 / g.max;
  }
  if (name == "ext-schlick" || name == "ext-reinhard-devlin" || name == "chiu" ||
      name == "retinex" || name == "ashikhmin" || name == "reinhard") {
    for (int q = 1; q <= u.r; ++q) {
      const auto kernel = gauss_weights(q, q / 2.5);
      u.w.insert(u.w.end(), kernel.begin(), kernel.end());
    }
  }
  assert(u.w.size() <= static_cast<size_t>(kWeights));
  return u;
}

}  // namespace relief::gpuprocess
