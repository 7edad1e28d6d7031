#include "talus/particles/body_shape.hpp"

#include "talus/core/polygon.hpp"

namespace talus {

bool body_contains(const BodySpec& body, const Vec3& p) {
  switch (body.shape) {
    case BodyShapeKind::Box:
      for (int d = 0; d < 3; ++d)
        if (!(p[d] >= body.box_min[d] && p[d] < body.box_max[d])) return false;
      return true;
    case BodyShapeKind::Prism:
      return p[1] >= body.prism.y0 && p[1] < body.prism.y1 && polygon_contains(body.prism.points, p[0], p[2]);
  }
  return false;
}

const char* to_string(BodyShapeKind shape) {
  switch (shape) {
    case BodyShapeKind::Box: return "box";
    case BodyShapeKind::Prism: return "prism";
  }
  return "?";
}

}  // namespace talus
