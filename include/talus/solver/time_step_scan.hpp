#pragma once
// The time step's scan (Edo & Matsubara 2015, eq. 60: dt = alpha h / max_p (c_p + |v_p|)) over a
// run of particles whose bodies share one wave-speed rule, several particles per instruction
// (Google Highway, run-time dispatch; core/simd_dispatch.hpp). Each lane does the scalar scan's
// operations in its order (c = sqrt(M V / m), |v| = sqrt((vx^2 + vy^2) + vz^2), c + |v|), and a
// maximum has no rounding, so every instruction set gives the scalar scan's time step bit for bit.
#include <array>
#include <cstddef>

namespace talus {

struct WaveRateFields {
  const double* volume = nullptr;
  const double* volume0 = nullptr;
  const double* mass = nullptr;
  std::array<const double*, 3> v{};
};

/// The wave-speed rule shared by every body: c = sqrt(modulus V / m), with V counted at most as
/// cap_ratio V0 when cap_ratio > 0 (BodyMaterials::wave_speed_volume).
struct WaveRateRule {
  double modulus = 0.0;
  double cap_ratio = 0.0;
};

/// max(0, max over [begin, end) of c_p + |v_p|); a NaN rate is skipped, as std::max(max, NaN) does.
double max_wave_rate_lanes(const WaveRateFields& fields, const WaveRateRule& rule, std::size_t begin, std::size_t end);

}  // namespace talus
