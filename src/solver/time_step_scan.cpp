// The time step's scan in lanes, compiled once per instruction set by Highway's foreach_target and
// dispatched at run time (header: solver/time_step_scan.hpp). Only Mul, Div, Add and Sqrt
// (correctly rounded on every target), never MulAdd: the scalar scan has no fused multiply-add.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "solver/time_step_scan.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <cmath>

#include "talus/solver/time_step_scan.hpp"

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// The scalar scan's rate of one particle (Solver::stable_time_step), for the tail.
inline double rate_of(const WaveRateFields& f, const WaveRateRule& rule, std::size_t p) {
  double volume = f.volume[p];
  if (rule.cap_ratio > 0.0 && volume > rule.cap_ratio * f.volume0[p]) volume = rule.cap_ratio * f.volume0[p];
  const double c = std::sqrt(rule.modulus * volume / f.mass[p]);
  const double speed = std::sqrt(f.v[0][p] * f.v[0][p] + f.v[1][p] * f.v[1][p] + f.v[2][p] * f.v[2][p]);
  return c + speed;
}

double MaxWaveRate(const WaveRateFields& f, const WaveRateRule& rule, std::size_t begin, std::size_t end) {
  const hn::ScalableTag<double> d;
  const std::size_t N = hn::Lanes(d);
  const auto modulus = hn::Set(d, rule.modulus), cap_ratio = hn::Set(d, rule.cap_ratio);
  const bool capped = rule.cap_ratio > 0.0;
  auto best = hn::Zero(d);
  std::size_t p = begin;
  for (; p + N <= end; p += N) {
    auto volume = hn::LoadU(d, f.volume + p);
    if (capped) {
      const auto cap = hn::Mul(cap_ratio, hn::LoadU(d, f.volume0 + p));
      volume = hn::IfThenElse(hn::Gt(volume, cap), cap, volume);
    }
    const auto c = hn::Sqrt(hn::Div(hn::Mul(modulus, volume), hn::LoadU(d, f.mass + p)));
    const auto vx = hn::LoadU(d, f.v[0] + p), vy = hn::LoadU(d, f.v[1] + p), vz = hn::LoadU(d, f.v[2] + p);
    const auto speed = hn::Sqrt(hn::Add(hn::Add(hn::Mul(vx, vx), hn::Mul(vy, vy)), hn::Mul(vz, vz)));
    const auto rate = hn::Add(c, speed);
    best = hn::IfThenElse(hn::Lt(best, rate), rate, best);  // std::max(best, rate): a NaN rate is skipped
  }
  double lanes[HWY_MAX_BYTES / sizeof(double)];
  hn::StoreU(best, d, lanes);
  double result = 0.0;
  for (std::size_t l = 0; l < N; ++l) result = result < lanes[l] ? lanes[l] : result;
  for (; p < end; ++p) {
    const double rate = rate_of(f, rule, p);
    result = result < rate ? rate : result;
  }
  return result;
}

}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace talus {

HWY_EXPORT(MaxWaveRate);

double max_wave_rate_lanes(const WaveRateFields& fields, const WaveRateRule& rule, std::size_t begin, std::size_t end) {
  return HWY_DYNAMIC_DISPATCH(MaxWaveRate)(fields, rule, begin, end);
}

}  // namespace talus
#endif
