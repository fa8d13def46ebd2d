#pragma once
// Mapping functions shared by the global tone-mapping operators and their
// locally adaptive SAR extensions (seed 003 §2.2.5), on amplitudes normalised
// to [0, 1]: the extensions replace the amplitude in one term by a' (Eq. 2.17).
#include <cmath>

#include "relief/process/dynamic_range.h"

namespace relief::process {

// Schlick's b when the user leaves it to "auto": the mean maps to mid-grey.
double auto_schlick_b(const GlobalStats& g);
// Reinhard-Devlin's m = 0.3 + 0.7 ((1 - a_avg) / (1 - a_min))^1.4 (Eq. 2.10).
double reinhard_devlin_exponent(const GlobalStats& g);

// g = b a / ((b - 1) a' + 1) (Eq. 2.8, 2.15).
inline double schlick(double a, double a_prime, double b) {
  return b * a / ((b - 1) * a_prime + 1);
}

// g = a / (a + (exp(-b) l)^m), l = (1 - c) a' + c a_avg (Eq. 2.9-2.11, 2.16).
class ReinhardDevlin {
 public:
  ReinhardDevlin(const GlobalStats& g, double b, double c)
      : m_(reinhard_devlin_exponent(g)), f_(std::exp(-b)), c_(c), avg_(g.mean / g.max) {}
  double operator()(double a, double a_prime) const {
    const double l = (1 - c_) * a_prime + c_ * avg_;
    const double sigma = std::pow(f_ * l, m_);
    return a + sigma > 0 ? a / (a + sigma) : 0.0;
  }

 private:
  double m_, f_, c_, avg_;
};

}  // namespace relief::process
