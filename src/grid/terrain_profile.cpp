#include "talus/grid/terrain_profile.hpp"

#include "talus/core/error.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

namespace talus {

double TerrainProfile::Piece::height(double x) const {
  if (!arc) return z0 + k * (x - x0);
  const double u = std::clamp(x - cx, -r, r);
  return cz + sign * std::sqrt(r * r - u * u);
}

double TerrainProfile::Piece::slope(double x) const {
  if (!arc) return k;
  const double u = std::clamp(x - cx, -r, r);
  const double root = std::sqrt(std::max(r * r - u * u, 1e-300));
  return -sign * u / root;
}

// On an arc the tangent angle phi = atan(z_b') turns uniformly with arc length: ds = r dphi.
double TerrainProfile::Piece::length_to(double x) const {
  if (!arc) return (x - x0) * std::sqrt(1.0 + k * k);
  return r * std::abs(std::atan(slope(x)) - std::atan(slope(x0)));
}

double TerrainProfile::Piece::x_at(double ds) const {
  if (!arc) return x0 + ds / std::sqrt(1.0 + k * k);
  // concave up (sign = -1): the slope grows along the arc; the point of tangent angle phi is
  // C + r (sin phi, -cos phi); concave down: C + r (-sin phi, cos phi).
  const double phi = std::atan(slope(x0)) - sign * ds / r;
  return cx - sign * r * std::sin(phi);
}

TerrainProfile::TerrainProfile(const TerrainSpec& spec) : spec_(spec) {
  const auto& P = spec.points;
  const std::size_t n = P.size();
  if (n < 2) throw input_error(fmt::format("points: {} given, at least 2 (x, z) points needed", n));
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(P[i][0]) || !std::isfinite(P[i][1]))
      throw input_error(fmt::format("points[{}]: must be finite", i));
    if (i > 0 && !(P[i][0] > P[i - 1][0]))
      throw input_error(fmt::format("points[{}]: x = {} must be greater than the previous x = {}", i,
                                    P[i][0], P[i - 1][0]));
  }
  if (!spec.radii.empty() && spec.radii.size() != n)
    throw input_error(fmt::format("radii: {} given, one per point ({}) or none", spec.radii.size(), n));
  const auto radius = [&](std::size_t i) { return spec.radii.empty() ? 0.0 : spec.radii[i]; };
  for (std::size_t i = 0; i < n; ++i)
    if (!(radius(i) >= 0.0) || !std::isfinite(radius(i)))
      throw input_error(fmt::format("radii[{}]: {} must be >= 0 (0 = sharp kink)", i, radius(i)));

  // Tangent points of each transition: A before the vertex, B after it.
  std::vector<std::array<double, 2>> a(n), b(n);
  std::vector<double> turn(n, 0.0), tangent(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) a[i] = b[i] = P[i];
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double ta = std::atan2(P[i][1] - P[i - 1][1], P[i][0] - P[i - 1][0]);
    const double tb = std::atan2(P[i + 1][1] - P[i][1], P[i + 1][0] - P[i][0]);
    turn[i] = tb - ta;
    if (radius(i) <= 0.0 || std::abs(turn[i]) < 1e-12) continue;
    tangent[i] = radius(i) * std::tan(0.5 * std::abs(turn[i]));
    a[i] = {P[i][0] - tangent[i] * std::cos(ta), P[i][1] - tangent[i] * std::sin(ta)};
    b[i] = {P[i][0] + tangent[i] * std::cos(tb), P[i][1] + tangent[i] * std::sin(tb)};
  }
  for (std::size_t i = 1; i < n; ++i) {
    // the segment from vertex i-1 to i must hold the end of the transition at i-1 and the start of
    // the one at i
    if (a[i][0] < b[i - 1][0] - 1e-12 * (1.0 + std::abs(P[i][0]))) {
      // Each transition takes its tangent length r tan(|turn|/2) of the segment: say how long the
      // segment is, what the transitions ask of it, and the largest radius each may have with the
      // other's as given (the message named both points, one of them with no transition, and no range).
      const double length = std::hypot(P[i][0] - P[i - 1][0], P[i][1] - P[i - 1][1]);
      std::string takes, allowed;
      for (const std::size_t k : {i - 1, i}) {
        if (tangent[k] <= 0.0) continue;
        const double other = k == i ? tangent[i - 1] : tangent[i];
        takes += fmt::format("{}radii[{}] = {} takes {:.4g} m", takes.empty() ? "" : ", ", k, radius(k), tangent[k]);
        allowed += fmt::format("{}radii[{}] <= {:.4g}", allowed.empty() ? "" : " or ",
                               k, std::max(0.0, length - other) / std::tan(0.5 * std::abs(turn[k])));
      }
      throw input_error(fmt::format(
          "radii: the transitions do not fit on the {:.4g} m segment from point {} to point {} ({}): allowed "
          "{}{}",
          length, i - 1, i, takes, allowed,
          tangent[i - 1] > 0.0 && tangent[i] > 0.0 ? " (each with the other's as given)" : ""));
    }
  }

  // Pieces: line to A, arc A..B, line to the next A, ...
  auto add_line = [&](const std::array<double, 2>& from, const std::array<double, 2>& to) {
    if (!(to[0] - from[0] > 1e-12 * (1.0 + std::abs(from[0])))) return;
    Piece p;
    p.x0 = from[0];
    p.x1 = to[0];
    p.z0 = from[1];
    p.k = (to[1] - from[1]) / (to[0] - from[0]);
    pieces_.push_back(p);
  };
  std::array<double, 2> start = P[0];
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (tangent[i] > 0.0) {
      add_line(start, a[i]);
      const double ta = std::atan2(P[i][1] - P[i - 1][1], P[i][0] - P[i - 1][0]);
      Piece arc;
      arc.arc = true;
      arc.x0 = a[i][0];
      arc.x1 = b[i][0];
      arc.r = radius(i);
      const double side = turn[i] > 0.0 ? 1.0 : -1.0;  // left turn: concave up, centre above
      arc.cx = a[i][0] - side * arc.r * std::sin(ta);
      arc.cz = a[i][1] + side * arc.r * std::cos(ta);
      arc.sign = -side;
      pieces_.push_back(arc);
      start = b[i];
    } else {
      add_line(start, P[i]);
      if (std::abs(turn[i]) >= 1e-12) kinks_.push_back(P[i][0]);
      start = P[i];
    }
  }
  add_line(start, P[n - 1]);
  double s = 0.0;
  for (auto& p : pieces_) {
    p.s0 = s;
    s += p.length_to(p.x1);
  }
}

const TerrainProfile::Piece& TerrainProfile::piece_at(double x) const {
  // the first piece whose end lies at or beyond x (the last one beyond the profile)
  auto it = std::lower_bound(pieces_.begin(), pieces_.end(), x, [](const Piece& p, double v) { return p.x1 < v; });
  if (it == pieces_.end()) --it;
  return *it;
}

double TerrainProfile::height(double x) const { return piece_at(x).height(x); }
double TerrainProfile::slope(double x) const { return piece_at(x).slope(x); }

Vec3 TerrainProfile::normal(double x) const {
  const double k = slope(x);
  return Vec3(-k, 0.0, 1.0) / std::sqrt(1.0 + k * k);
}

double TerrainProfile::arc_length(double x) const {
  const Piece& p = piece_at(x);
  return p.s0 + p.length_to(x);
}

double TerrainProfile::x_at_arc_length(double s) const {
  auto it = std::upper_bound(pieces_.begin(), pieces_.end(), s, [](double v, const Piece& p) { return v < p.s0; });
  if (it != pieces_.begin()) --it;
  return it->x_at(s - it->s0);
}

std::optional<double> TerrainProfile::last_segment_start() const {
  const std::size_t n = spec_.points.size();
  if (n < 3) return std::nullopt;
  const auto& a = spec_.points[n - 3];
  const auto& v = spec_.points[n - 2];  // the last interior vertex
  const auto& b = spec_.points[n - 1];
  const double r = spec_.radii.empty() ? 0.0 : spec_.radii[n - 2];
  const double in = std::atan2(v[1] - a[1], v[0] - a[0]);
  const double out = std::atan2(b[1] - v[1], b[0] - v[0]);
  // A fillet of radius r tangent to both segments touches them at the distance r tan(|turn| / 2)
  // from the vertex (the tangent length of a circular curve).
  const double tangent_length = r * std::tan(0.5 * std::abs(out - in));
  return v[0] + tangent_length * std::cos(out);
}

std::array<double, 2> TerrainProfile::height_range(double x0, double x1) const {
  double lo = std::min(height(x0), height(x1)), hi = std::max(height(x0), height(x1));
  for (const Piece& p : pieces_) {
    const double candidates[3] = {p.x0, p.x1, p.arc ? p.cx : p.x0};  // vertices and an arc's extremum
    for (double x : candidates) {
      if (x <= x0 || x >= x1) continue;
      const double z = height(x);
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
  }
  return {lo, hi};
}

}  // namespace talus
