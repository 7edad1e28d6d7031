#include "talus/core/polygon.hpp"

#include <algorithm>
#include <cmath>

namespace talus {

namespace {

using Point = std::array<double, 2>;

double cross(const Point& o, const Point& p, const Point& q) {
  return (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
}

bool on_segment_box(const Point& p, const Point& q, const Point& r) {
  return std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= r[1] &&
         r[1] <= std::max(p[1], q[1]);
}

// Whether the closed segments pq and rs share a point (orientation test, collinear cases included).
bool segments_touch(const Point& p, const Point& q, const Point& r, const Point& s) {
  const double d1 = cross(r, s, p), d2 = cross(r, s, q), d3 = cross(p, q, r), d4 = cross(p, q, s);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  if (d1 == 0 && on_segment_box(r, s, p)) return true;
  if (d2 == 0 && on_segment_box(r, s, q)) return true;
  if (d3 == 0 && on_segment_box(p, q, r)) return true;
  if (d4 == 0 && on_segment_box(p, q, s)) return true;
  return false;
}

}  // namespace

bool polygon_contains(const PolygonPoints& polygon, double a, double b) {
  // Crossing number (Shimrat 1962; O'Rourke, Computational Geometry in C, sec. 7.4): count the
  // edges crossed by the ray from (a, b) towards +a. An edge counts when it straddles the line
  // v = b with one end strictly above and the other on or below (half-open in v), and the
  // crossing lies strictly right of a (half-open in a).
  bool inside = false;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Point& p = polygon[i];
    const Point& q = polygon[j];
    if ((p[1] > b) != (q[1] > b)) {
      const double crossing = p[0] + (b - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
      if (a < crossing) inside = !inside;
    }
  }
  return inside;
}

double polygon_signed_area(const PolygonPoints& polygon) {
  double twice = 0.0;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++)
    twice += polygon[j][0] * polygon[i][1] - polygon[i][0] * polygon[j][1];
  return 0.5 * twice;
}

std::array<int, 2> polygon_crossing_edges(const PolygonPoints& polygon) {
  const int n = static_cast<int>(polygon.size());
  auto a = [&](int i) { return polygon[i % n]; };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const bool neighbours = j == i + 1 || (i == 0 && j == n - 1);
      if (!neighbours) {
        if (segments_touch(a(i), a(i + 1), a(j), a(j + 1))) return {i, j};
        continue;
      }
      // Neighbours share one vertex; they must not fold back onto each other (collinear overlap)
      // or repeat a vertex (a zero-length edge).
      const Point shared = j == i + 1 ? a(j) : a(i);
      const Point u = j == i + 1 ? a(i) : a(i + 1);
      const Point w = j == i + 1 ? a(j + 1) : a(j);
      if ((u[0] == shared[0] && u[1] == shared[1]) || (w[0] == shared[0] && w[1] == shared[1])) return {i, j};
      if (cross(shared, u, w) == 0.0) {
        const double dot = (u[0] - shared[0]) * (w[0] - shared[0]) + (u[1] - shared[1]) * (w[1] - shared[1]);
        if (dot > 0.0) return {i, j};
      }
    }
  return {-1, -1};
}

}  // namespace talus
