#include "talus/scene/scene_json.hpp"

#include "json_fields.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace talus {

using scene_detail::Json;
using scene_detail::ObjectReader;

namespace {

constexpr double kHuge = 1e30;
const char* const kFaceNames[3][2] = {{"x-", "x+"}, {"y-", "y+"}, {"z-", "z+"}};

void read_grid(ObjectReader r, Scene& s) {
  s.grid.origin = r.vec3_or("origin", Vec3::Zero());
  const double h = r.number("cell_size", 0.0, kHuge, true);
  const Vec3 size = r.vec3("size", 0.0, kHuge);
  s.grid.h = h;
  for (int d = 0; d < 3; ++d) {
    const double n = size[d] / h;
    const long long cells = std::llround(n);
    if (cells < 1 || std::abs(n - static_cast<double>(cells)) > 1e-6 * std::max(1.0, n))
      throw input_error(fmt::format("{}[{}] = {} must be a positive whole multiple of {} = {}", r.key_path("size"), d,
                                    size[d], r.key_path("cell_size"), h));
    if (cells > 100000)
      throw input_error(fmt::format("{}[{}] / cell_size = {} cells; at most 100000 per axis", r.key_path("size"), d, cells));
    s.grid.cells[d] = static_cast<int>(cells);
  }
  r.finish();
}

void read_time(ObjectReader r, Scene& s) {
  s.end_time = r.number("end", 0.0, kHuge, true);
  s.courant = r.number_or("courant", s.courant, 0.0, 1.0, true, true);
  s.max_steps = r.integer_or("max_steps", 0, 0, 2000000000);
  r.finish();
}

void read_solver(ObjectReader r, Scene& s) {
  const std::string scheme = r.choice("scheme", "musl", {"musl", "usl"});
  s.scheme = scheme == "musl" ? SchemeKind::Musl : SchemeKind::Usl;
  r.choice("shape", "linear", {"linear"});
  s.shape = ShapeKind::Linear;
  s.sort_interval = r.integer_or("sort_interval", s.sort_interval, 1, 1000000);
  r.finish();
}

MaterialSpec read_material(ObjectReader r, const std::string& name) {
  MaterialSpec m;
  m.name = name;
  r.choice("model", "linear_elastic", {"linear_elastic"});
  m.density = r.number("density", 0.0, kHuge, true);
  m.elastic.young = r.number("young", 0.0, kHuge, true);
  m.elastic.poisson = r.number("poisson", -1.0, 0.5, true, true);
  r.finish();
  return m;
}

BodySpec read_body(ObjectReader r, const Scene& s, const std::map<std::string, int>& materials) {
  BodySpec b;
  b.name = r.string("name");
  const std::string material = r.string("material");
  auto it = materials.find(material);
  if (it == materials.end()) {
    std::string known;
    for (const auto& [k, v] : materials) known += (known.empty() ? "" : ", ") + k;
    throw input_error(fmt::format("{} = \"{}\" names no material (defined: {})", r.key_path("material"), material, known));
  }
  b.material = it->second;
  ObjectReader box = r.object("box");
  b.box_min = box.vec3("min");
  b.box_max = box.vec3("max");
  box.finish();
  for (int d = 0; d < 3; ++d) {
    const double lo = s.grid.origin[d];
    const double hi = lo + s.grid.cells[d] * s.grid.h;
    if (!(b.box_min[d] < b.box_max[d]))
      throw input_error(fmt::format("{}.min[{}] = {} must be below max[{}] = {}", box.path(), d, b.box_min[d], d, b.box_max[d]));
    if (b.box_min[d] < lo - 1e-12 * std::abs(lo) || b.box_max[d] > hi + 1e-12 * std::abs(hi))
      throw input_error(fmt::format("{} [{}, {}] along axis {} lies outside the grid [{}, {}]", box.path(), b.box_min[d],
                                    b.box_max[d], d, lo, hi));
  }
  b.particles_per_cell = r.integer_or("particles_per_cell", b.particles_per_cell, 1, 8);
  b.velocity = r.vec3_or("velocity", Vec3::Zero());
  r.finish();
  return b;
}

WallSpec read_wall(const Json& j, const std::string& path) {
  WallSpec w;
  auto parse_type = [&](const std::string& t, const std::string& at) {
    if (t == "open") return WallType::Open;
    if (t == "slip") return WallType::Slip;
    if (t == "fixed") return WallType::Fixed;
    if (t == "friction") return WallType::Friction;
    throw input_error(fmt::format("{} = \"{}\" is not one of: open, slip, fixed, friction", at, t));
  };
  if (j.is_string()) {
    w.type = parse_type(j.get<std::string>(), path);
    if (w.type == WallType::Friction)
      throw input_error(fmt::format("{} = \"friction\" needs an object with friction_coefficient", path));
    return w;
  }
  ObjectReader r(j, path);
  w.type = parse_type(r.string("type"), r.key_path("type"));
  if (w.type == WallType::Friction) w.friction_coefficient = r.number("friction_coefficient", 0.0, 100.0);
  r.finish();
  return w;
}

void read_boundaries(ObjectReader r, Scene& s) {
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side)
      if (r.has(kFaceNames[d][side])) s.walls[d][side] = read_wall(r.raw(kFaceNames[d][side]), r.key_path(kFaceNames[d][side]));
  r.finish();
}

void read_output(ObjectReader r, Scene& s) {
  s.output.frame_interval = r.number_or("frame_interval", 0.0, 0.0, kHuge);
  s.output.history_interval = r.number_or("history_interval", 0.0, 0.0, kHuge);
  s.output.compress = r.choice("compression", "lz4", {"lz4", "none"}) == "lz4";
  r.finish();
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& source) {
  Json root;
  try {
    root = Json::parse(text);
  } catch (const Json::parse_error& e) {
    // nlohmann's message already names the line and column.
    std::string what = e.what();
    throw input_error(fmt::format("{}: malformed JSON: {}", source, what.substr(what.find(']') + 2)));
  }
  Scene s;
  ObjectReader r(root, "");
  r.allow("comment");
  s.name = r.string_or("name", "scene");
  s.description = r.string_or("description", "");
  read_grid(r.object("grid"), s);
  s.gravity = r.vec3_or("gravity", s.gravity);
  read_time(r.object("time"), s);
  if (r.has("solver")) read_solver(r.object("solver"), s);

  std::map<std::string, int> material_index;
  {
    ObjectReader mats = r.object("materials");
    const Json& mj = root.at("materials");
    for (auto it = mj.begin(); it != mj.end(); ++it) {
      mats.allow(it.key());
      material_index[it.key()] = static_cast<int>(s.materials.size());
      s.materials.push_back(read_material(ObjectReader(it.value(), mats.key_path(it.key())), it.key()));
    }
    if (s.materials.empty()) throw input_error("materials must define at least one material");
  }
  {
    const Json& bj = r.raw("bodies");
    if (!bj.is_array() || bj.empty()) throw input_error("bodies must be a non-empty array of bodies");
    if (bj.size() > 65535) throw input_error("bodies: at most 65535 bodies");
    for (std::size_t i = 0; i < bj.size(); ++i)
      s.bodies.push_back(read_body(ObjectReader(bj[i], fmt::format("bodies[{}]", i)), s, material_index));
  }
  if (r.has("boundaries")) read_boundaries(r.object("boundaries"), s);
  if (r.has("output")) read_output(r.object("output"), s);
  r.finish();
  return s;
}

Scene read_scene_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw input_error(fmt::format("cannot open scene file {}", path));
  std::stringstream text;
  text << in.rdbuf();
  return parse_scene(text.str(), path);
}

nlohmann::json scene_to_json(const Scene& s) {
  auto vec = [](const Vec3& v) { return Json::array({v[0], v[1], v[2]}); };
  Json j;
  j["name"] = s.name;
  j["description"] = s.description;
  j["grid"] = {{"origin", vec(s.grid.origin)},
               {"cell_size", s.grid.h},
               {"size", Json::array({s.grid.cells[0] * s.grid.h, s.grid.cells[1] * s.grid.h, s.grid.cells[2] * s.grid.h})}};
  j["gravity"] = vec(s.gravity);
  j["time"] = {{"end", s.end_time}, {"courant", s.courant}, {"max_steps", s.max_steps}};
  j["solver"] = {{"scheme", to_string(s.scheme)}, {"shape", to_string(s.shape)}, {"sort_interval", s.sort_interval}};
  Json mats = Json::object();
  for (const auto& m : s.materials)
    mats[m.name] = {{"model", "linear_elastic"}, {"density", m.density}, {"young", m.elastic.young}, {"poisson", m.elastic.poisson}};
  j["materials"] = mats;
  Json bodies = Json::array();
  for (const auto& b : s.bodies)
    bodies.push_back({{"name", b.name},
                      {"material", s.materials[b.material].name},
                      {"box", {{"min", vec(b.box_min)}, {"max", vec(b.box_max)}}},
                      {"particles_per_cell", b.particles_per_cell},
                      {"velocity", vec(b.velocity)}});
  j["bodies"] = bodies;
  Json walls = Json::object();
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      const WallSpec& w = s.walls[d][side];
      if (w.type == WallType::Friction)
        walls[kFaceNames[d][side]] = {{"type", "friction"}, {"friction_coefficient", w.friction_coefficient}};
      else
        walls[kFaceNames[d][side]] = to_string(w.type);
    }
  j["boundaries"] = walls;
  j["output"] = {{"frame_interval", s.output.frame_interval},
                 {"history_interval", s.output.history_interval},
                 {"compression", s.output.compress ? "lz4" : "none"}};
  return j;
}

}  // namespace talus
