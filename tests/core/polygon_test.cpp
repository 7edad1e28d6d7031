// Plane polygons (core/polygon.hpp): inside test with half-open edges, area, self-crossing.
#include "talus/core/polygon.hpp"

#include <gtest/gtest.h>

namespace talus {
namespace polygon_test {
namespace {

const PolygonPoints kSquare{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
const PolygonPoints kRightSquare{{1, 0}, {2, 0}, {2, 1}, {1, 1}};

TEST(Polygon, InsideOutsideAndSharedEdgesBelongToOne) {
  EXPECT_TRUE(polygon_contains(kSquare, 0.5, 0.5));
  EXPECT_FALSE(polygon_contains(kSquare, 1.5, 0.5));
  EXPECT_FALSE(polygon_contains(kSquare, 0.5, -0.1));
  // A point on the edge the two squares share belongs to exactly one of them.
  for (const double b : {0.25, 0.5, 0.75})
    EXPECT_NE(polygon_contains(kSquare, 1.0, b), polygon_contains(kRightSquare, 1.0, b)) << b;
  // Non-convex: an L shape does not hold its notch.
  const PolygonPoints l{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  EXPECT_TRUE(polygon_contains(l, 0.5, 1.5));
  EXPECT_FALSE(polygon_contains(l, 1.5, 1.5));
}

TEST(Polygon, SignedAreaAndCrossingEdges) {
  EXPECT_DOUBLE_EQ(polygon_signed_area(kSquare), 1.0);
  const PolygonPoints clockwise(kSquare.rbegin(), kSquare.rend());
  EXPECT_DOUBLE_EQ(polygon_signed_area(clockwise), -1.0);
  EXPECT_EQ(polygon_crossing_edges(kSquare), (std::array<int, 2>{-1, -1}));
  const PolygonPoints bow_tie{{0, 0}, {1, 1}, {1, 0}, {0, 1}};  // edges 0 and 2 cross
  EXPECT_EQ(polygon_crossing_edges(bow_tie), (std::array<int, 2>{0, 2}));
}

}  // namespace
}  // namespace polygon_test
}  // namespace talus
