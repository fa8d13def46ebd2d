#include "relief/gpuprocess/chain.h"

#include <algorithm>
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
  // Only what the output needs: the border beyond the chain's margin and the
  // one sample kept is cropped before the first step, not after the last
  // (each output sample depends only on the input around it, so the values
  // are the same). The tile is read in place; the last step writes the
  // result.
  const int crop = border - 1 - chain_margin(chain);
  const int stride = tile.width();
  int w = tile.width() - 2 * crop, h = tile.height() - 2 * crop;
  tiles::Raster out(tiles::SampleType::Float32, 1, w - 2 * chain_margin(chain),
                    h - 2 * chain_margin(chain));
  process::ConstView in{
      tile.f32().data() + static_cast<size_t>(crop) * stride + crop, w, h, stride, crop, crop};
  if (chain.steps.empty()) {
    for (int y = 0; y < out.height(); ++y) {
      std::copy_n(in.row(y), out.width(), &out.f32()[static_cast<size_t>(y) * out.width()]);
    }
    return out;
  }
  std::vector<float> buffers[2];
  for (size_t i = 0; i < chain.steps.size(); ++i) {
    const auto& s = chain.steps[i];
    const int m = process::margin_of(*s.op, s.params);
    const int ow = w - 2 * m, oh = h - 2 * m;
    float* dst = out.f32().data();
    if (i + 1 < chain.steps.size()) {
      std::vector<float>& next = buffers[i % 2];
      next.resize(static_cast<size_t>(ow) * static_cast<size_t>(oh));
      dst = next.data();
    }
    const process::MutView o{dst, ow, oh, ow, in.origin_x + m, in.origin_y + m};
    RELIEF_CHECK(process::run_operator(*s.op, s.params, in, o, executor, stats));
    in = o;
    w = ow, h = oh;
  }
  return out;
}

}  // namespace relief::gpuprocess
