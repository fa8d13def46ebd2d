// The manifest's fields must agree with each other: a reader trusts the kind
// to pick colours or elevations, the sample type to size buffers, the codec to
// decode, so a manifest that contradicts itself is refused when read.
#include <fmt/format.h>

#include "relief/tiles/manifest.h"

namespace relief::tiles {

namespace {

SampleType sample_type_of(DatasetKind kind) {
  return kind == DatasetKind::Imagery ? SampleType::UInt8 : SampleType::Float32;
}

int bands_of(SampleType type) {
  return type == SampleType::UInt8 ? 4 : 1;
}

}  // namespace

Status check_consistency(const Manifest& m, const std::string& name) {
  if (m.sample_type != sample_type_of(m.kind)) {
    return fail(fmt::format("{}: kind {} needs {} samples, not {}", name, to_string(m.kind),
                            to_string(sample_type_of(m.kind)), to_string(m.sample_type)));
  }
  if (m.bands != bands_of(m.sample_type)) {
    return fail(fmt::format("{}: {} samples come in {} band(s), not {}", name,
                            to_string(m.sample_type), bands_of(m.sample_type), m.bands));
  }
  if (!codec_supports(m.codec.codec, m.sample_type)) {
    return fail(fmt::format("{}: codec {} cannot store {} samples", name, to_string(m.codec.codec),
                            to_string(m.sample_type)));
  }
  if (!(m.codec.max_error >= 0)) {
    return fail(fmt::format("{}: codec max_error {} is negative", name, m.codec.max_error));
  }
  const bool has_quality = m.codec.codec == Codec::Jpeg || m.codec.codec == Codec::Webp;
  if (has_quality && !(m.codec.quality >= 1 && m.codec.quality <= 100)) {
    return fail(fmt::format("{}: codec quality {} is not in 1..100", name, m.codec.quality));
  }
  const geo::GeoBox& e = m.extent;
  if (!(e.west <= e.east && e.south <= e.north)) {
    return fail(fmt::format("{}: extent W {} S {} E {} N {} is not west <= east, south <= north",
                            name, e.west, e.south, e.east, e.north));
  }
  if (m.stats.valid_count > 0 && !(m.stats.min <= m.stats.max && m.stats.stddev >= 0)) {
    return fail(fmt::format("{}: statistics min {} max {} std {} contradict each other", name,
                            m.stats.min, m.stats.max, m.stats.stddev));
  }
  return {};
}

}  // namespace relief::tiles
