#include "relief/gpuprocess/chain.h"

#include <cmath>

#include <fmt/format.h>

namespace relief::gpuprocess {

Result<ChainStep> make_step(const std::string& op, const std::vector<std::string>& assignments) {
  const process::OperatorSpec* spec = process::find_operator(op);
  if (!spec) return fail(fmt::format("unknown operator '{}' (relief process --list)", op));
  return ChainStep{spec, RELIEF_TRY(process::parse_params(*spec, assignments))};
}

OperatorChain scale_chain(const OperatorChain& chain, double factor) {
  OperatorChain scaled;
  for (const auto& s : chain.steps) {
    scaled.steps.push_back({s.op, process::scale_params(*s.op, s.params, factor)});
  }
  return scaled;
}

int chain_margin(const OperatorChain& chain) {
  int m = 0;
  for (const auto& s : chain.steps) m += process::margin_of(*s.op, s.params);
  return m;
}

Status check_fits(const OperatorChain& chain, int border) {
  if (border < 1) {
    return fail(
        fmt::format("the tile has a {}-sample border; processing needs at least 1", border));
  }
  int used = 0;
  for (const auto& s : chain.steps) {
    const int m = process::margin_of(*s.op, s.params);
    used += m;
    if (used > border - 1) {
      return fail(fmt::format(
          "{}: needs a {}-sample margin ({} for the chain so far), more than the {} of the tile's "
          "{}-sample overlap border left after the output's one-sample border",
          s.op->name, m, used, border - 1, border));
    }
  }
  return {};
}

Status check_stats(const OperatorChain& chain, const process::GlobalStats* stats) {
  for (const auto& s : chain.steps) {
    if (!s.op->needs_global_stats) continue;
    if (!stats) return fail(fmt::format("{}: needs the dataset's global statistics", s.op->name));
    if (!(stats->max > stats->min) || !(stats->stddev > 0) || !(stats->max > 0)) {
      return fail(fmt::format("{}: the data has no dynamic range to reduce", s.op->name));
    }
    if (s.op->name == "log") {
      const double t_min = std::isnan(s.params.at("t_min")) ? stats->min : s.params.at("t_min");
      const double t_max =
          std::isnan(s.params.at("t_max")) ? stats->mean + 3 * stats->stddev : s.params.at("t_max");
      if (!(t_max > t_min)) {
        return fail(fmt::format("log: t_max ({}) must be greater than t_min ({})", t_max, t_min));
      }
    }
  }
  return {};
}

Status check_chain_for(const OperatorChain& chain, const tiles::Manifest& m,
                       const std::string& name) {
  for (const auto& s : chain.steps) {
    if (m.sample_type != tiles::SampleType::Float32) {
      return fail(fmt::format("{}: operator {} needs a single-band store, not RGBA {}", name,
                              s.op->name, tiles::to_string(m.kind)));
    }
    if (s.op->sar_only && m.kind != tiles::DatasetKind::Sar) {
      return fail(fmt::format("{}: operator {} expects {}, but the store holds {} data", name,
                              s.op->name, s.op->input, tiles::to_string(m.kind)));
    }
  }
  if (auto st = check_fits(chain, m.border); !st) {
    return fail(fmt::format("{}: {}", name, st.error().message));
  }
  const process::GlobalStats stats{m.stats.min, m.stats.max, m.stats.mean, m.stats.stddev};
  if (auto st = check_stats(chain, &stats); !st) {
    return fail(fmt::format("{}: {}", name, st.error().message));
  }
  return {};
}

Result<tiles::Raster> run_chain_cpu(const OperatorChain& chain, const tiles::Raster& tile,
                                    int border, const process::GlobalStats* stats,
                                    Executor& executor) {
  assert(tile.type() == tiles::SampleType::Float32 && tile.bands() == 1);
  RELIEF_CHECK(check_fits(chain, border));
  RELIEF_CHECK(check_stats(chain, stats));
  int w = tile.width(), h = tile.height();
  std::vector<float> current(tile.f32().begin(), tile.f32().end()), next;
  for (const auto& s : chain.steps) {
    const int m = process::margin_of(*s.op, s.params);
    const int ow = w - 2 * m, oh = h - 2 * m;
    next.assign(static_cast<size_t>(ow) * static_cast<size_t>(oh), 0.0f);
    RELIEF_CHECK(process::run_operator(*s.op, s.params, {current.data(), w, h, w, 0, 0},
                                       {next.data(), ow, oh, ow, m, m}, executor, stats));
    current.swap(next);
    w = ow, h = oh;
  }
  // What is left of the border beyond the one sample the output keeps.
  const int crop = border - 1 - chain_margin(chain);
  tiles::Raster out(tiles::SampleType::Float32, 1, w - 2 * crop, h - 2 * crop);
  auto dst = out.f32();
  for (int y = 0; y < out.height(); ++y) {
    for (int x = 0; x < out.width(); ++x) {
      dst[static_cast<size_t>(y) * out.width() + x] =
          current[static_cast<size_t>(y + crop) * w + x + crop];
    }
  }
  return out;
}

}  // namespace relief::gpuprocess
