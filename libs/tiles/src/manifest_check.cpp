// The manifest's fields must agree with each other: a reader trusts the kind
// to pick colours or elevations, the sample type to size buffers, the codec to
// decode, so a manifest that contradicts itself is refused when read.
#include <algorithm>
#include <cmath>
#include <limits>

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
  // Longitudes may reach past the antimeridian (a grid of 0..360 wrapped to
  // -180..180 starts half a sample west of -180), never past a full turn.
  const geo::GeoBox& e = m.extent;
  if (!(e.west < e.east && e.south < e.north) || !(e.west >= -360 && e.east <= 360) ||
      !(e.south >= -90 && e.north <= 90)) {
    return fail(fmt::format(
        "{}: extent W {} S {} E {} N {} is not west < east within -360..360 and south < north "
        "within -90..90",
        name, e.west, e.south, e.east, e.north));
  }
  const SampleStats& s = m.stats;
  if (s.valid_count > 0 && !(s.min <= s.max && s.stddev >= 0 && std::isfinite(s.stddev))) {
    return fail(fmt::format("{}: statistics min {} max {} std {} contradict each other", name,
                            s.min, s.max, s.stddev));
  }
  // Statistics of samples lie within what the sample type holds.
  const double lowest = m.sample_type == SampleType::UInt8 ? 0 : -std::numeric_limits<float>::max();
  const double highest =
      m.sample_type == SampleType::UInt8 ? 255 : std::numeric_limits<float>::max();
  // The mean, a sum divided, may round past min or max by an ulp or so.
  const double slack = 1e-9 * std::max({1.0, std::abs(s.min), std::abs(s.max)});
  if (s.valid_count > 0 && !(s.min >= lowest && s.max <= highest && s.mean >= s.min - slack &&
                             s.mean <= s.max + slack)) {
    return fail(fmt::format(
        "{}: statistics min {} max {} mean {} are not {} sample values with min <= mean <= max",
        name, s.min, s.max, s.mean, to_string(m.sample_type)));
  }
  return {};
}

}  // namespace relief::tiles
