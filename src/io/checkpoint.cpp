#include "talus/io/checkpoint.hpp"

#include "talus/core/error.hpp"
#include "talus/core/version.hpp"
#include "talus/particles/particle_migration.hpp"
#include "talus/scene/scene_json.hpp"

#include <H5Cpp.h>
#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <unistd.h>
#include <limits>
#include <memory>
#include <set>
#include <type_traits>

namespace talus {

namespace {

constexpr const char* kFormat = "talus-checkpoint";
constexpr int kFormatVersion = 3;  // 2: outflow through open faces; 3: the energy ledger's names

/// The /solver attributes of the outflow by face (OutflowFaces' order). outflow_mass_x_plus was
/// kept before the others; all are read as 0 (counted from the restart) from a checkpoint without
/// them, as the version did not change.
constexpr std::array<const char*, OutflowFaces::kFaces> kOutflowMassNames = {
    "outflow_mass_x_minus", "outflow_mass_x_plus", "outflow_mass_y_minus",
    "outflow_mass_y_plus",  "outflow_mass_z_minus", "outflow_mass_z_plus"};
constexpr std::array<const char*, OutflowFaces::kFaces> kOutflowParticleNames = {
    "outflow_particles_x_minus", "outflow_particles_x_plus", "outflow_particles_y_minus",
    "outflow_particles_y_plus",  "outflow_particles_z_minus", "outflow_particles_z_plus"};

template <class T>
const H5::PredType& h5_type();
template <>
const H5::PredType& h5_type<double>() { return H5::PredType::NATIVE_DOUBLE; }
template <>
const H5::PredType& h5_type<std::int64_t>() { return H5::PredType::NATIVE_INT64; }
template <>
const H5::PredType& h5_type<std::int32_t>() { return H5::PredType::NATIVE_INT32; }
template <>
const H5::PredType& h5_type<std::uint16_t>() { return H5::PredType::NATIVE_UINT16; }
template <>
const H5::PredType& h5_type<std::uint32_t>() { return H5::PredType::NATIVE_UINT32; }
template <>
const H5::PredType& h5_type<std::uint64_t>() { return H5::PredType::NATIVE_UINT64; }
template <>
const H5::PredType& h5_type<char>() { return H5::PredType::NATIVE_CHAR; }

template <class T>
void write_attribute(H5::H5Object& where, const char* name, T value) {
  H5::Attribute a = where.createAttribute(name, h5_type<T>(), H5::DataSpace(H5S_SCALAR));
  a.write(h5_type<T>(), &value);
}
void write_attribute(H5::H5Object& where, const char* name, const std::string& value) {
  H5::StrType type(H5::PredType::C_S1, std::max<std::size_t>(value.size(), 1));
  H5::Attribute a = where.createAttribute(name, type, H5::DataSpace(H5S_SCALAR));
  a.write(type, value.empty() ? std::string(" ").c_str() : value.c_str());
}

template <class T>
T read_attribute(const H5::H5Object& where, const char* name) {
  T value{};
  where.openAttribute(name).read(h5_type<T>(), &value);
  return value;
}
std::string read_string_attribute(const H5::H5Object& where, const char* name) {
  H5::Attribute a = where.openAttribute(name);
  std::string value;
  a.read(a.getStrType(), value);
  return value;
}

template <class T, class Allocator>
void write_array(H5::Group& group, const std::string& name, const std::vector<T, Allocator>& data) {
  const hsize_t n = data.size();
  H5::DataSpace space(1, &n);
  H5::DataSet set = group.createDataSet(name, h5_type<T>(), space);
  if (n) set.write(data.data(), h5_type<T>());
}

template <class T>
std::vector<T> read_array(const H5::Group& group, const std::string& name) {
  H5::DataSet set = group.openDataSet(name);
  H5::DataSpace space = set.getSpace();
  const std::string file = group.getFileName();
  if (space.getSimpleExtentNdims() != 1)
    throw io_error(fmt::format("checkpoint {} is damaged: dataset {} is not one-dimensional", file, name));
  hsize_t n = 0;
  space.getSimpleExtentDims(&n);
  // A damaged header's length is refused before it is allocated (2e9 values asked for 16 GB from a
  // file of 200 kB): no dataset holds more values than the file has bytes for.
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(file, ec);
  if (!ec && n > bytes / sizeof(T))
    throw io_error(fmt::format("checkpoint {} is damaged: dataset {} claims {} values, more than its {} bytes hold", file,
                               name, n, bytes));
  std::vector<T> data(n);
  if (n) set.read(data.data(), h5_type<T>());
  return data;
}

/// The run's and the solver's scalars a step could have left: a damaged or edited value (a time of
/// NaN stepped forever, writing nothing; a schedule time of NaN wrote no frame) is refused.
void check_scalars(const Checkpoint& c, const std::string& path) {
  auto refuse = [&](const std::string& what) {
    throw input_error(fmt::format("checkpoint {} is inconsistent: {}", path, what));
  };
  const SolverState& s = c.solver;
  if (!(std::isfinite(s.time) && s.time >= 0.0)) refuse(fmt::format("its time is {} s", s.time));
  if (s.step < 0) refuse(fmt::format("its step is {}", s.step));
  if (!(std::isfinite(s.last_dt) && s.last_dt >= 0.0)) refuse(fmt::format("its last time step is {} s", s.last_dt));
  if (!(std::isfinite(s.outflow_mass) && s.outflow_mass >= 0.0)) refuse(fmt::format("its outflow mass is {} kg", s.outflow_mass));
  for (int face = 0; face < OutflowFaces::kFaces; ++face)
    if (!(std::isfinite(s.outflow_faces.mass[face]) && s.outflow_faces.mass[face] >= 0.0) || s.outflow_faces.particles[face] < 0)
      refuse(fmt::format("its outflow through {} is {} kg, {} particles", OutflowFaces::kNames[face],
                         s.outflow_faces.mass[face], s.outflow_faces.particles[face]));
  for (const auto& [name, value] : {std::pair{"next_frame", c.run.next_frame}, std::pair{"next_history", c.run.next_history},
                                    std::pair{"next_checkpoint", c.run.next_checkpoint}})
    if (!std::isfinite(value)) refuse(fmt::format("/run {} is {}", name, value));
  if (c.run.frame_times.size() != c.run.frame_steps.size())
    refuse(fmt::format("{} frame times for {} frame steps", c.run.frame_times.size(), c.run.frame_steps.size()));
  for (std::size_t i = 0; i < c.run.frame_times.size(); ++i)
    if (!std::isfinite(c.run.frame_times[i]) || c.run.frame_steps[i] < 0 ||
        (i > 0 && !(c.run.frame_times[i] >= c.run.frame_times[i - 1])))
      refuse(fmt::format("frame {} is at t = {} s, step {}", i, c.run.frame_times[i], c.run.frame_steps[i]));
}

/// Values [first, first + count) of a one-dimensional dataset of `total` values (a rank's part of
/// a particle array); the dataset's length is checked against `total`.
template <class T>
std::vector<T> read_array_part(const H5::Group& group, const std::string& name, hsize_t first, hsize_t count,
                               hsize_t total) {
  H5::DataSet set = group.openDataSet(name);
  H5::DataSpace space = set.getSpace();
  hsize_t n = 0;
  if (space.getSimpleExtentNdims() != 1 || (space.getSimpleExtentDims(&n), n != total))
    throw io_error(fmt::format("checkpoint {} is inconsistent: {} does not hold the {} particles its ranks saved",
                               group.getFileName(), name, total));
  std::vector<T> data(count);
  if (count == 0) return data;
  space.selectHyperslab(H5S_SELECT_SET, &count, &first);
  H5::DataSpace memory(1, &count);
  set.read(data.data(), h5_type<T>(), memory, space);
  return data;
}

/// A JSON value on one short line: numbers as the shortest text that reads back (2, not 2.0), and
/// anything longer than 40 characters cut with "...".
std::string short_json(const nlohmann::json& value) {
  std::string text = value.is_number_float() ? fmt::format("{}", value.get<double>()) : value.dump(-1, ' ', true);
  constexpr std::size_t kMost = 40;
  if (text.size() > kMost) text = text.substr(0, kMost - 3) + "...";
  return text;
}

std::string first_difference(const nlohmann::json& saved, const nlohmann::json& current) {
  const nlohmann::json patch = nlohmann::json::diff(saved, current);
  if (patch.empty()) return "";
  // A material's model first: it explains the keys that come and go with it (a Drucker-Prager
  // checkpoint against an elastic scene named /materials/m/cohesion).
  auto op = patch.begin();
  for (auto it = patch.begin(); it != patch.end(); ++it) {
    const std::string path = it->value("path", std::string());
    if (path.size() >= 6 && path.compare(path.size() - 6, 6, "/model") == 0) {
      op = it;
      break;
    }
  }
  const std::string kind = op->value("op", std::string());
  const std::string path = op->value("path", std::string("/"));
  // The two values, short: which key differs said too little to find the edit ("/time/end (differs)").
  auto value_at = [&](const nlohmann::json& scene) -> std::string {
    try {
      return short_json(scene.at(nlohmann::json::json_pointer(path)));
    } catch (const nlohmann::json::exception&) {
      return "?";
    }
  };
  // (JSON Patch's words, from the checkpoint's scene to this one: "remove" read like an instruction)
  if (kind == "add") return fmt::format("{}: only in this scene, {}", path, value_at(current));
  if (kind == "remove") return fmt::format("{}: only in the checkpoint's scene, {}", path, value_at(saved));
  return fmt::format("{}: checkpoint {}, this scene {}", path, value_at(saved), value_at(current));
}

/// The scene's JSON without, or with only, the keys a restart may change (restart_changes).
nlohmann::json changeable_part(const nlohmann::json& scene, bool keep) {
  static const char* const kTimeKeys[] = {"end", "courant", "max_steps"};
  nlohmann::json part = keep ? nlohmann::json::object() : scene;
  if (!scene.is_object()) return part;
  // The scene's notes, and how often checkpoints are written (a completed run without periodic
  // checkpoints could never be extended: the interval it would need was a change refused)
  for (const char* key : {"description", "comment"})
    if (scene.contains(key)) {
      if (keep)
        part[key] = scene[key];
      else
        part.erase(key);
    }
  if (auto o = scene.find("output"); o != scene.end() && o->is_object() && o->contains("checkpoint_interval")) {
    if (keep)
      part["output"]["checkpoint_interval"] = (*o)["checkpoint_interval"];
    else
      part["output"].erase("checkpoint_interval");
  }
  if (auto t = scene.find("time"); t != scene.end() && t->is_object())
    for (const char* key : kTimeKeys) {
      if (!t->contains(key)) continue;
      if (keep)
        part["time"][key] = (*t)[key];
      else
        part["time"].erase(key);
    }
  if (auto g = scene.find("guards"); g != scene.end()) {
    if (keep)
      part["guards"] = *g;
    else
      part.erase("guards");
  }
  return part;
}

}  // namespace

std::vector<std::string> restart_changes(const Checkpoint& checkpoint, const Scene& scene) {
  nlohmann::json saved;
  try {
    saved = nlohmann::json::parse(checkpoint.scene_json);
  } catch (const nlohmann::json::exception&) {
    return {};  // (restore_checkpoint refuses it)
  }
  const nlohmann::json now = scene_to_json(scene);
  const nlohmann::json before = changeable_part(saved, true), after = changeable_part(now, true);
  std::vector<std::string> lines;
  for (const nlohmann::json& op : nlohmann::json::diff(before, after)) {
    const std::string pointer = op.value("path", std::string());
    std::string key = pointer.substr(1);
    std::replace(key.begin(), key.end(), '/', '.');
    auto value_in = [&](const nlohmann::json& j) {
      const nlohmann::json::json_pointer at(pointer);
      return j.contains(at) ? short_json(j.at(at)) : std::string("(not set)");
    };
    lines.push_back(fmt::format("{}: {} in the checkpoint's scene, {} here", key, value_in(before), value_in(after)));
  }
  return lines;
}

std::string scene_hash(const Scene& scene) {
  const std::string text = scene_to_json(scene).dump();
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

namespace {

/// The scalars of a rank's SolverState kept per rank, by name, in one order: f(name, value,
/// required). Not required: the energy gap terms and the outflow by face, absent in checkpoints
/// written before them.
template <class State, class F>
void for_each_rank_scalar(State& s, F&& f) {
  EnergyBudget::for_each_term(s.work, [&](const char* name, auto& value, bool accumulated) {
    if (accumulated) f(name, value, true);
  });
  f("outflow_mass", s.outflow_mass, true);
  for (int face = 0; face < OutflowFaces::kFaces; ++face) f(kOutflowMassNames[face], s.outflow_faces.mass[face], false);
  f("periodic_gravity_shift", s.periodic_gravity_shift, true);
  EnergyGapTerms::for_each_term(s.gap, [&](const char* name, auto& value) { f(name, value, false); });
}
/// The same for the integers: f(name, value, required).
template <class State, class F>
void for_each_rank_integer(State& s, F&& f) {
  f("outflow_particles", s.outflow_particles, true);
  for (int face = 0; face < OutflowFaces::kFaces; ++face)
    f(kOutflowParticleNames[face], s.outflow_faces.particles[face], false);
  f("sorts", s.sorts, true);
  f("steps_since_sort", s.steps_since_sort, true);
  f("needs_sort", s.needs_sort, true);
}

}  // namespace

void write_checkpoint(const std::string& path, const Solver& solver, const RunProgress& run) {
  const std::string tmp = path + ".tmp";
  const Scene& scene = solver.scene();
  const Comm& comm = solver.comm();
  SolverState state = solver.state();
  // A distributed run: every rank's particles (rank after rank), its sort cells and its scalars on
  // rank 0; the attributes hold the sums over the ranks, so one rank can restart from them too.
  const AllParticles all(comm, solver.particles());
  const ParticleStore& P = all.get();
  std::vector<std::int64_t> rank_particles;
  std::map<std::string, std::vector<double>> rank_scalars;
  std::map<std::string, std::vector<std::int64_t>> rank_integers;
  if (comm.distributed()) {
    for (auto& c : state.sort_cell) c = comm.gather(c);
    rank_particles = comm.gather(std::vector<std::int64_t>{static_cast<std::int64_t>(solver.particles().size())});
    for_each_rank_scalar(state, [&](const char* name, double& value, bool) {
      rank_scalars[name] = comm.gather(std::vector<double>{value});
      value = comm.sum_in_rank_order(value);
    });
    for_each_rank_integer(state, [&](const char* name, auto& value, bool) {
      rank_integers[name] = comm.gather(std::vector<std::int64_t>{static_cast<std::int64_t>(value)});
    });
    state.outflow_particles = comm.sum_in_rank_order(std::vector<std::int64_t>{state.outflow_particles})[0];
    for (auto& count : state.outflow_faces.particles) count = comm.sum_in_rank_order(std::vector<std::int64_t>{count})[0];
    state.needs_sort = comm.any(state.needs_sort);
    if (!comm.root()) return;
  }
  try {
    H5::Exception::dontPrint();
    {
      H5::H5File file(tmp, H5F_ACC_TRUNC);
      write_attribute(file, "format", std::string(kFormat));
      write_attribute(file, "format_version", kFormatVersion);
      write_attribute(file, "talus_version", std::string(kVersion));
      write_attribute(file, "scene_hash", scene_hash(scene));
      write_attribute(file, "scene_name", scene.name);
      const std::string json = scene_to_json(scene).dump(2);
      {
        H5::Group root = file.openGroup("/");
        write_array(root, "scene_json", std::vector<char>(json.begin(), json.end()));
      }
      H5::Group s = file.createGroup("/solver");
      write_attribute(s, "time", state.time);
      write_attribute(s, "step", state.step);
      write_attribute(s, "last_dt", state.last_dt);
      EnergyBudget::for_each_term(state.work, [&](const char* name, double value, bool accumulated) {
        if (accumulated) write_attribute(s, name, value);
      });
      write_attribute(s, "outflow_mass", state.outflow_mass);
      write_attribute(s, "outflow_particles", state.outflow_particles);
      for (int face = 0; face < OutflowFaces::kFaces; ++face) {
        write_attribute(s, kOutflowMassNames[face], state.outflow_faces.mass[face]);
        write_attribute(s, kOutflowParticleNames[face], state.outflow_faces.particles[face]);
      }
      write_attribute(s, "steps_since_sort", static_cast<std::int32_t>(state.steps_since_sort));
      write_attribute(s, "sorts", state.sorts);
      write_attribute(s, "needs_sort", static_cast<std::int32_t>(state.needs_sort));
      write_attribute(s, "periodic_gravity_shift", state.periodic_gravity_shift);
      EnergyGapTerms::for_each_term(state.gap, [&](const char* name, double value) { write_attribute(s, name, value); });
      write_attribute(s, "sort_drift", state.sort_drift);
      for (int d = 0; d < 3; ++d) write_array(s, fmt::format("sort_cell{}", d), state.sort_cell[d]);
      if (state.mls_weights) {  // the `reused` MLS variant: its weights, so that a restart reuses them
        H5::Group w = file.createGroup("/solver/mls_weights");
        write_attribute(w, "strain_since_fit", state.mls_strain_since_fit);
        std::vector<std::uint64_t> offsets;
        std::vector<std::uint32_t> neighbour;
        std::vector<double> phi;
        state.mls_weights->flatten(offsets, neighbour, phi);
        write_array(w, "offsets", offsets);
        write_array(w, "neighbour", neighbour);
        write_array(w, "phi", phi);
      }
      if (comm.distributed()) {
        H5::Group ranks = file.createGroup("/solver/ranks");
        write_array(ranks, "particles", rank_particles);
        const auto& first = solver.decomposition().first_columns();
        write_array(ranks, "slab_first_columns", std::vector<std::int32_t>(first.begin(), first.end()));
        for (const auto& [name, values] : rank_scalars) write_array(ranks, name, values);
        for (const auto& [name, values] : rank_integers) write_array(ranks, name, values);
      }

      H5::Group p = file.createGroup("/particles");
      P.for_each_double_array([&](const char* name, const ParticleArray<double>& a) {
        if (!a.empty()) write_array(p, name, a);
      });
      P.for_each_integer_array([&](const char* name, const auto& a) { write_array(p, name, a); });

      H5::Group r = file.createGroup("/run");
      write_attribute(r, "next_frame", run.next_frame);
      write_attribute(r, "next_history", run.next_history);
      write_attribute(r, "next_checkpoint", run.next_checkpoint);
      EnergyBudget::for_each_term(run.initial, [&](const char* name, double value, bool) {
        write_attribute(r, (std::string("initial_") + name).c_str(), value);
      });
      write_attribute(r, "energy_max_released", run.energy_max_released);
      if (run.energy_warning) {
        write_attribute(r, "energy_warning_step", run.energy_warning->step);
        write_attribute(r, "energy_warning_time", run.energy_warning->time);
        write_attribute(r, "energy_warning_share", run.energy_warning->share);
      }
      if (!run.runout_first_row.empty()) write_attribute(r, "runout_first_row", run.runout_first_row);
      if (!run.frame_folders.empty()) write_attribute(r, "frame_folders", nlohmann::json(run.frame_folders).dump());
      write_array(r, "frame_times", run.frame_times);
      write_array(r, "frame_steps", run.frame_steps);
      file.close();
    }
  } catch (const H5::Exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw io_error(fmt::format("cannot write checkpoint {}: {} ({})", path, e.getDetailMsg(), e.getFuncName()));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw io_error(fmt::format("cannot write checkpoint {}: {}", path, ec.message()));
}

int checkpoint_ranks(const std::string& path) {
  try {
    H5::Exception::dontPrint();
    H5::H5File file(path, H5F_ACC_RDONLY);
    H5::Group s = file.openGroup("/solver");
    if (!s.nameExists("ranks")) return 1;
    H5::DataSpace space = s.openGroup("ranks").openDataSet("particles").getSpace();
    hsize_t n = 0;
    if (space.getSimpleExtentNdims() != 1) return 0;
    space.getSimpleExtentDims(&n);
    return static_cast<int>(std::min<hsize_t>(n, 1 << 30));
  } catch (const H5::Exception&) {
    return 0;
  }
}

std::optional<std::pair<double, std::int64_t>> checkpoint_time_and_step(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  try {
    H5::Exception::dontPrint();
    H5::H5File file(path, H5F_ACC_RDONLY);
    H5::Group s = file.openGroup("/solver");
    return std::make_pair(read_attribute<double>(s, "time"), read_attribute<std::int64_t>(s, "step"));
  } catch (const H5::Exception&) {
    return std::nullopt;
  }
}

Checkpoint read_checkpoint(const std::string& path, const Comm& comm) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw input_error(fmt::format("cannot open checkpoint {}: {}", path,
                                  !std::filesystem::exists(path, ec)       ? "no such file"
                                  : std::filesystem::is_directory(path, ec) ? "it is a folder, not a file"
                                                                            : "not a regular file"));
  Checkpoint c;
  try {
    H5::Exception::dontPrint();
    // (a file of another kind said "is not readable: H5Fopen failed")
    if (::access(path.c_str(), R_OK) != 0)
      throw input_error(fmt::format("cannot open checkpoint {}: no read permission", path));
    if (H5Fis_hdf5(path.c_str()) <= 0)
      throw input_error(fmt::format("checkpoint {} is not an HDF5 file (a talus checkpoint is one: runs/<name>/checkpoint.h5)", path));
    H5::H5File file(path, H5F_ACC_RDONLY);
    H5::Group root = file.openGroup("/");
    if (!root.attrExists("format") || read_string_attribute(root, "format") != kFormat)
      throw input_error(fmt::format("{} is not a talus checkpoint", path));
    const int format_version = read_attribute<int>(root, "format_version");
    if (format_version != kFormatVersion)
      throw input_error(fmt::format("checkpoint {} has format version {}; this talus reads version {}", path,
                                    format_version, kFormatVersion));
    c.talus_version = read_string_attribute(root, "talus_version");
    c.scene_hash = read_string_attribute(root, "scene_hash");
    c.scene_name = read_string_attribute(root, "scene_name");
    const std::vector<char> json = read_array<char>(root, "scene_json");
    c.scene_json.assign(json.begin(), json.end());

    H5::Group s = file.openGroup("/solver");
    c.solver.time = read_attribute<double>(s, "time");
    c.solver.step = read_attribute<std::int64_t>(s, "step");
    c.solver.last_dt = read_attribute<double>(s, "last_dt");
    // (gravity_ramp is absent in checkpoints written before 2026-12-07: 0, as for a run without a ramp)
    const auto absent_before_ramp_term = [](const H5::H5Object& o, const std::string& name) {
      return name.ends_with("gravity_ramp") && !o.attrExists(name);
    };
    EnergyBudget::for_each_term(c.solver.work, [&](const char* name, double& value, bool accumulated) {
      if (accumulated && !absent_before_ramp_term(s, name)) value = read_attribute<double>(s, name);
    });
    c.solver.outflow_mass = read_attribute<double>(s, "outflow_mass");
    c.solver.outflow_particles = read_attribute<std::int64_t>(s, "outflow_particles");
    // absent in checkpoints written before they were kept: counted from the restart
    for (int face = 0; face < OutflowFaces::kFaces; ++face) {
      if (s.attrExists(kOutflowMassNames[face]))
        c.solver.outflow_faces.mass[face] = read_attribute<double>(s, kOutflowMassNames[face]);
      if (s.attrExists(kOutflowParticleNames[face]))
        c.solver.outflow_faces.particles[face] = read_attribute<std::int64_t>(s, kOutflowParticleNames[face]);
    }
    c.solver.steps_since_sort = read_attribute<std::int32_t>(s, "steps_since_sort");
    c.solver.sorts = read_attribute<std::int64_t>(s, "sorts");
    c.solver.needs_sort = read_attribute<std::int32_t>(s, "needs_sort") != 0;
    // absent in checkpoints of runs before periodic faces existed: no wraps
    if (s.attrExists("periodic_gravity_shift"))
      c.solver.periodic_gravity_shift = read_attribute<double>(s, "periodic_gravity_shift");
    // absent in checkpoints written before output.energy_gap_terms existed: counted from the restart
    EnergyGapTerms::for_each_term(c.solver.gap, [&](const char* name, double& value) {
      if (s.attrExists(name)) value = read_attribute<double>(s, name);
    });
    // absent in checkpoints of runs that sorted every step with MLS: the next step sorts
    c.solver.sort_drift = s.attrExists("sort_drift") ? read_attribute<double>(s, "sort_drift")
                                                     : std::numeric_limits<double>::infinity();
    if (s.nameExists("ranks")) {
      H5::Group ranks = s.openGroup("ranks");
      c.rank_particles = read_array<std::int64_t>(ranks, "particles");
      c.slab_first_columns = read_array<std::int32_t>(ranks, "slab_first_columns");
      c.rank_states.assign(c.rank_particles.size(), c.solver);
      for (std::size_t r = 0; r < c.rank_states.size(); ++r) {
        for_each_rank_scalar(c.rank_states[r], [&](const char* name, double& value, bool required) {
          if (required || ranks.nameExists(name)) value = read_array<double>(ranks, name).at(r);
        });
        for_each_rank_integer(c.rank_states[r], [&](const char* name, auto& value, bool required) {
          if (required || ranks.nameExists(name))
            value = static_cast<std::remove_reference_t<decltype(value)>>(read_array<std::int64_t>(ranks, name).at(r));
        });
      }
    }

    // On the saved number of ranks a rank reads only its own saved particles.
    hsize_t first = 0, count = 0, total = 0;
    for (std::size_t r = 0; r < c.rank_particles.size(); ++r) {
      if (c.rank_particles[r] < 0) throw input_error(fmt::format("checkpoint {} is inconsistent: rank {} saved {} particles", path, r, c.rank_particles[r]));
      if (r < static_cast<std::size_t>(comm.rank())) first += static_cast<hsize_t>(c.rank_particles[r]);
      total += static_cast<hsize_t>(c.rank_particles[r]);
    }
    c.own_part = comm.distributed() && c.rank_particles.size() == static_cast<std::size_t>(comm.size());
    if (c.own_part) count = static_cast<hsize_t>(c.rank_particles[comm.rank()]);
    const auto particle_array = [&]<class T>(const H5::Group& group, const std::string& name, T) {
      return c.own_part ? read_array_part<T>(group, name, first, count, total) : read_array<T>(group, name);
    };
    for (int d = 0; d < 3; ++d) c.solver.sort_cell[d] = particle_array(s, fmt::format("sort_cell{}", d), std::int32_t{});
    // absent where the scene is not the `reused` MLS variant, or had no weights yet: the next pass fits
    if (s.nameExists("mls_weights")) {
      H5::Group w = s.openGroup("mls_weights");
      std::vector<std::uint64_t> offsets = read_array<std::uint64_t>(w, "offsets");
      std::vector<std::uint32_t> neighbour = read_array<std::uint32_t>(w, "neighbour");
      std::vector<double> phi = read_array<double>(w, "phi");
      auto weights = std::make_shared<MlsStoredWeights>();
      if (!weights->assign(offsets, neighbour, phi))
        throw input_error(fmt::format("checkpoint {}: its MLS weights are inconsistent", path));
      c.solver.mls_weights = std::move(weights);
      c.solver.mls_strain_since_fit = read_attribute<double>(w, "strain_since_fit");
    }

    H5::Group p = file.openGroup("/particles");
    c.id = particle_array(p, "id", std::int64_t{});
    c.body = particle_array(p, "body", std::uint16_t{});
    for (hsize_t i = 0; i < p.getNumObjs(); ++i) {
      const std::string name = p.getObjnameByIdx(i);
      if (name == "id" || name == "body") continue;
      c.double_arrays[name] = particle_array(p, name, double{});
    }

    H5::Group r = file.openGroup("/run");
    c.run.next_frame = read_attribute<double>(r, "next_frame");
    c.run.next_history = read_attribute<double>(r, "next_history");
    c.run.next_checkpoint = read_attribute<double>(r, "next_checkpoint");
    EnergyBudget::for_each_term(c.run.initial, [&](const char* name, double& value, bool) {
      const std::string attribute = std::string("initial_") + name;
      if (!absent_before_ramp_term(r, attribute)) value = read_attribute<double>(r, attribute.c_str());
    });
    c.run.energy_max_released = read_attribute<double>(r, "energy_max_released");
    if (r.attrExists("energy_warning_step"))
      c.run.energy_warning = EnergyWarning{read_attribute<std::int64_t>(r, "energy_warning_step"),
                                           read_attribute<double>(r, "energy_warning_time"),
                                           read_attribute<double>(r, "energy_warning_share")};
    // absent in checkpoints written before 2026-12-06 and in scenes without runout diagnostics
    if (r.attrExists("runout_first_row")) c.run.runout_first_row = read_string_attribute(r, "runout_first_row");
    // absent in checkpoints written before it was kept; one that does not parse is as good as absent
    // (it only says where the earlier frames are)
    if (r.attrExists("frame_folders")) try {
        c.run.frame_folders = nlohmann::json::parse(read_string_attribute(r, "frame_folders"))
                                  .get<std::vector<std::pair<std::size_t, std::string>>>();
      } catch (const nlohmann::json::exception&) {
        c.run.frame_folders.clear();
      }
    c.run.frame_times = read_array<double>(r, "frame_times");
    c.run.frame_steps = read_array<std::int64_t>(r, "frame_steps");
    check_scalars(c, path);
  } catch (const H5::Exception& e) {
    throw input_error(fmt::format("checkpoint {} is not readable: {}", path, e.getDetailMsg()));
  }
  return c;
}

namespace {

/// The checkpoint's particles in the scene's layout, after the checks one rank makes alone: the
/// version, the scene, every array the layout has (and no other) at the particles' count, the body
/// indices, and the ranks' counts.
ParticleStore checked_particles(const Solver& solver, const Checkpoint& c, const std::string& path) {
  if (c.talus_version != kVersion)
    throw input_error(fmt::format("checkpoint {} was written by talus {}; this is talus {}: restart with that version",
                                  path, c.talus_version, kVersion));
  const std::string hash = scene_hash(solver.scene());
  if (c.scene_hash != hash) {
    // The keys a restart may change (restart_changes) aside, the scenes must be the same.
    std::string diff = "?";
    try {
      diff = first_difference(changeable_part(nlohmann::json::parse(c.scene_json), false),
                              changeable_part(scene_to_json(solver.scene()), false));
    } catch (const std::exception&) {
    }
    if (diff.empty()) {
      if (solver.scene().end_time < c.solver.time)
        throw input_error(fmt::format("time.end = {} s is before the checkpoint's time, t = {:.6g} s: a restart goes on "
                                      "from there", solver.scene().end_time, c.solver.time));
      if (solver.scene().max_steps > 0 && solver.scene().max_steps < c.solver.step)
        throw input_error(fmt::format("time.max_steps = {} is below the checkpoint's step, {}: a restart goes on from "
                                      "there (0: no limit)", solver.scene().max_steps, c.solver.step));
      diff = "";
    }
    if (!diff.empty()) throw input_error(fmt::format(
        "checkpoint {} belongs to another scene (\"{}\", hash {}; this scene \"{}\" hashes to {}){}: a restart needs "
        "the scene the checkpoint was written with (only time.end, time.courant, time.max_steps, guards.*, output.checkpoint_interval, description and comment may change)",
        path, c.scene_name, c.scene_hash, solver.scene().name, hash, diff == "?" ? "" : ", first difference at " + diff));
  }
  const std::size_t n = c.id.size();
  auto bad = [&](const std::string& what) { return input_error(fmt::format("checkpoint {} is inconsistent: {}", path, what)); };
  if (c.body.size() != n) throw bad("body has another length than id");
  ParticleStore P = solver.particles();  // the scene's layout: which arrays are allocated
  std::set<std::string> used;
  P.for_each_double_array([&](const char* name, ParticleArray<double>& a) {
    if (!P.has_array(name)) return;
    auto it = c.double_arrays.find(name);
    if (it == c.double_arrays.end()) throw bad(fmt::format("particle array {} is missing", name));
    if (it->second.size() != n) throw bad(fmt::format("particle array {} has {} values for {} particles", name, it->second.size(), n));
    a.assign(it->second.begin(), it->second.end());
    used.insert(name);
  });
  for (const auto& [name, a] : c.double_arrays)
    if (!used.count(name)) throw bad(fmt::format("particle array {} is not used by this scene", name));
  P.id.assign(c.id.begin(), c.id.end());
  P.body.assign(c.body.begin(), c.body.end());
  for (std::uint16_t b : P.body)
    if (b >= solver.scene().bodies.size()) throw bad("a particle's body index is out of range");
  std::int64_t saved = 0;
  for (std::int64_t count : c.rank_particles) saved += count;
  if (c.own_part) saved = c.rank_particles[solver.comm().rank()];
  if (!c.rank_particles.empty() && saved != static_cast<std::int64_t>(n))
    throw bad("the ranks' particle counts do not add up to the particles");
  for (const auto& cells : c.solver.sort_cell)
    if (!c.rank_particles.empty() && cells.size() != n) throw bad("the sort cells are not one a particle");
  return P;
}

/// Each rank's particles and state into the solver: on the saved number of ranks bit for bit, on
/// another number dealt to new slabs (collective).
void restore_particles(Solver& solver, ParticleStore P, const Checkpoint& c) {
  const Comm& comm = solver.comm();
  const std::size_t saved_ranks = c.rank_particles.empty() ? 1 : c.rank_particles.size();
  if (saved_ranks == static_cast<std::size_t>(comm.size())) {
    if (!comm.distributed()) {
      solver.restore(std::move(P), c.solver);
      return;
    }
    // The same number of ranks: each takes its saved particles (all it read, when it read its own
    // part), sort cells, counters and ledger.
    std::int64_t first = 0;
    for (int r = 0; r < comm.rank() && !c.own_part; ++r) first += c.rank_particles[r];
    const std::int64_t count = c.rank_particles[comm.rank()];
    if (!c.own_part) {
      std::vector<std::uint32_t> mine(static_cast<std::size_t>(count));
      for (std::int64_t i = 0; i < count; ++i) mine[i] = static_cast<std::uint32_t>(first + i);
      P.permute(mine);
    }
    SolverState state = c.rank_states[comm.rank()];
    for (int d = 0; d < 3; ++d)
      state.sort_cell[d].assign(c.solver.sort_cell[d].begin() + first, c.solver.sort_cell[d].begin() + first + count);
    solver.set_slab_bounds(std::vector<int>(c.slab_first_columns.begin(), c.slab_first_columns.end()));
    solver.restore(std::move(P), state);
    return;
  }
  // Another number of ranks: new balanced slabs, a fresh sort; the sums of the ledger and counters
  // go to rank 0 (every rank's share adds up to them).
  SolverState state = c.solver;
  if (!comm.root()) {
    EnergyBudget::for_each_term(state.work, [](const char*, double& value, bool accumulated) {
      if (accumulated) value = 0.0;
    });
    state.outflow_mass = state.periodic_gravity_shift = 0.0;
    state.outflow_faces = OutflowFaces{};
    state.gap = EnergyGapTerms{};
    state.outflow_particles = 0;
  }
  for (auto& cells : state.sort_cell) cells.clear();
  solver.restore(solver.own_particles(std::move(P)), state, Solver::RestoreSort::Fresh);
}

}  // namespace

void restore_checkpoint(Solver& solver, const Checkpoint& c, const std::string& path) {
  ParticleStore P;
  // What each rank checks of the file alone; a rank that refuses it must not leave the others
  // waiting in the restore's collectives (Comm::agree).
  solver.comm().agree([&] { P = checked_particles(solver, c, path); });
  try {
    restore_particles(solver, std::move(P), c);
  } catch (const Error& e) {  // (the solver's checks of the particles do not know the file)
    throw Error(e.kind(), fmt::format("checkpoint {}: {}", path, e.what()));
  }
}

}  // namespace talus
