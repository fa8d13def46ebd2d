#pragma once
// Point-target detection and analysis in SAR amplitude images (seed 003
// §2.4.3). A point target's response is a bright peak with side lobes along
// two axes (a cross). The detector tests every sample:
//  1. amplitude at least `level` (15 %) of the dataset's maximum;
//  2. the maximum of its 7 x 7 neighbourhood (ties go to the first sample in
//     raster order, so a saturated plateau gives one detection);
//  3. mean amplitudes along 12 line masks through it, 0 to 165 degrees in
//     15-degree steps (3 samples either side, bilinear); the two highest
//     whose directions differ by at least 45 degrees are the side-lobe axes,
//     and both must reach `sensitivity` times the 7 x 7 mean.
// A rough PSLR comes from the 7 x 7 cross-sections. The analysis of one
// target samples long cross-sections along both axes and measures the peak
// side-lobe ratio and the -3 dB width of the main lobe.
//
// Directions are in degrees counter-clockwise from the image's +x (column)
// axis, with +y (rows) pointing down, in [0, 180).
#include <cstdint>
#include <vector>

#include "relief/process/view.h"

namespace relief::process {

inline constexpr int kDetectorMargin = 3;  // the 7 x 7 neighbourhood

struct DetectorParams {
  double level = 0.15;       // fraction of the maximum amplitude
  double sensitivity = 1.5;  // t: side-lobe means against the 7 x 7 mean
};

struct Detection {
  int64_t x = 0, y = 0;  // global sample coordinates (View::origin_x/y based)
  double amplitude = 0;
  double direction[2] = {0, 0};  // side-lobe axes, degrees
  double pslr_db = 0;            // rough: highest of the 7 x 7 cross-sections beyond the peak
};

// Detects targets centred in the output region: `in` extends kDetectorMargin
// beyond it on every side. Detections come in raster order.
std::vector<Detection> detect_point_targets(ConstView in, double max_amplitude,
                                            const DetectorParams& params);

struct CrossSection {
  double direction = 0;    // degrees
  std::vector<double> db;  // 20 log10(a / peak) at offsets -R..R (NaN: no data)
  double pslr_db = 0;      // highest side lobe beyond the first nulls, relative to the peak
  double width_3db = 0;    // main-lobe width at -3 dB, samples (linear interpolation)
};

struct TargetAnalysis {
  int64_t x = 0, y = 0;
  double amplitude = 0;
  int half_length = 0;  // R
  CrossSection axes[2];
  double pslr_db = 0;  // the worse (higher) of the two axes
};

// Cross-sections through the target at `d` along both axes; `in` holds the
// target with `half_length` + 1 samples around it.
TargetAnalysis analyse_point_target(ConstView in, const Detection& d, int half_length);

// A plot of both cross-sections (dB against offset) as RGBA pixels.
std::vector<uint8_t> plot_cross_sections(const TargetAnalysis& analysis, int width, int height);

}  // namespace relief::process
