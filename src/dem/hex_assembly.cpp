#include "talus/dem/hex_assembly.hpp"

#include "talus/dem/number_text.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <Eigen/SparseCholesky>

#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace talus::dem {
namespace {

constexpr int kFixed = -1;

struct DiscId {
  int row;
  int column;
};

// Even rows hold discs_per_row discs, odd rows one fewer, so that the block is symmetric about its
// vertical mid-line and, for an odd number of rows, about its middle row (see check_spec).
int discs_in_row(const HexAssemblySpec& spec, int row) { return spec.discs_per_row - (row % 2); }

// Unknowns per disc: u1, u2 and, when discs turn, w = a theta. Scaling the rotation by the radius keeps
// the matrix entries of one size whatever a is.
class DofMap {
 public:
  DofMap(const HexAssemblySpec& spec, bool with_rotation) : per_disc_(with_rotation ? 3 : 2) {
    int discs = 0;
    for (int row = 0; row < spec.rows; ++row) {
      first_disc_of_row_.push_back(discs);
      discs += discs_in_row(spec, row);
    }
    index_.assign(static_cast<std::size_t>(discs * per_disc_), 0);
    // Supports (Abe 1996, §3): bottom row vertically, bottom-left disc also horizontally.
    for (int column = 0; column < discs_in_row(spec, 0); ++column) index_[slot({0, column}, 1)] = kFixed;
    index_[slot({0, 0}, 0)] = kFixed;
    for (int& entry : index_) {
      if (entry != kFixed) entry = count_++;
    }
  }
  int count() const { return count_; }
  int operator()(DiscId disc, int component) const { return index_[slot(disc, component)]; }

 private:
  std::size_t slot(DiscId disc, int component) const {
    return static_cast<std::size_t>((first_disc_of_row_[disc.row] + disc.column) * per_disc_ + component);
  }
  int per_disc_;
  int count_ = 0;
  std::vector<int> first_disc_of_row_;
  std::vector<int> index_;
};

Vec2 centre_of(DiscId disc, double radius) {
  const double shift = (disc.row % 2 == 1) ? radius : 0.0;
  return {2.0 * radius * disc.column + shift, std::numbers::sqrt3 * radius * disc.row};
}

// Each touching pair once: the right-hand neighbour and the two neighbours in the row above.
std::vector<std::pair<DiscId, DiscId>> touching_pairs(const HexAssemblySpec& spec) {
  std::vector<std::pair<DiscId, DiscId>> pairs;
  for (int row = 0; row < spec.rows; ++row) {
    for (int column = 0; column < discs_in_row(spec, row); ++column) {
      const DiscId disc{row, column};
      if (column + 1 < discs_in_row(spec, row)) pairs.push_back({disc, {row, column + 1}});
      if (row + 1 < spec.rows) {
        // Odd rows start a to the right of even rows: above an even-row disc sit odd-row discs
        // column - 1 and column, above an odd-row disc even-row discs column and column + 1.
        const int left = (row % 2 == 0) ? column - 1 : column;
        for (int above = left; above <= left + 1; ++above) {
          if (above >= 0 && above < discs_in_row(spec, row + 1)) pairs.push_back({disc, {row + 1, above}});
        }
      }
    }
  }
  return pairs;
}

// The uniform state the exact loading reproduces: sigma_11 = stress, sigma_22 = sigma_12 = 0 in the
// plane-strain continuum of eq. 52 with the hexagonal lattice's G and nu (eq. 22, 33).
Mat2 uniaxial_plane_strain_gradient(const ContactSprings& springs, double stress) {
  const double shear = std::numbers::sqrt3 / 4.0 * (springs.normal + springs.tangential);
  const double poisson = 0.25 * (1.0 - springs.tangential_to_normal());
  Mat2 gradient = Mat2::Zero();
  gradient(0, 0) = stress * (1.0 - poisson) / (2.0 * shear);
  gradient(1, 1) = -stress * poisson / (2.0 * shear);
  return gradient;
}

// For every disc on the boundary, the unit vectors towards the lattice sites that hold no disc.
std::vector<std::pair<DiscId, std::vector<Vec2>>> missing_neighbours(
    const HexAssemblySpec& spec, const std::vector<std::pair<DiscId, DiscId>>& pairs) {
  const auto direction_index = [](const Vec2& n) {
    const int k = static_cast<int>(std::lround(std::atan2(n.y(), n.x()) / (std::numbers::pi / 3.0)));
    return (k + 6) % 6;
  };
  std::vector<std::vector<std::array<bool, 6>>> present(static_cast<std::size_t>(spec.rows));
  for (int row = 0; row < spec.rows; ++row) present[row].assign(discs_in_row(spec, row), {});
  for (const auto& [disc_a, disc_b] : pairs) {
    const Vec2 n = (centre_of(disc_b, spec.radius) - centre_of(disc_a, spec.radius)).normalized();
    present[disc_a.row][disc_a.column][direction_index(n)] = true;
    present[disc_b.row][disc_b.column][direction_index(-n)] = true;
  }
  std::vector<std::pair<DiscId, std::vector<Vec2>>> result;
  for (int row = 0; row < spec.rows; ++row) {
    for (int column = 0; column < discs_in_row(spec, row); ++column) {
      std::vector<Vec2> missing;
      for (int k = 0; k < 6; ++k) {
        if (present[row][column][k]) continue;
        const double angle = k * std::numbers::pi / 3.0;
        missing.push_back({std::cos(angle), std::sin(angle)});
      }
      if (!missing.empty()) result.push_back({{row, column}, std::move(missing)});
    }
  }
  return result;
}

void check_spec(const HexAssemblySpec& spec) {
  const int middle_row = spec.rows / 2;
  const int middle_column = discs_in_row(spec, middle_row) / 2;
  const bool gauges_fit = spec.gauge_columns >= 1 && spec.gauge_row_pairs >= 1 &&
                          middle_column - spec.gauge_columns >= 0 &&
                          middle_column + spec.gauge_columns < discs_in_row(spec, middle_row) &&
                          middle_row - 2 * spec.gauge_row_pairs >= 0 &&
                          middle_row + 2 * spec.gauge_row_pairs < spec.rows;
  // An odd number of rows puts even (long) rows at the top and bottom, so the block and its end
  // loads are symmetric about the middle row: the end loads then differ from the uniform-stress
  // contact forces only by a self-equilibrated set, whose effect dies out within a few discs of the
  // ends (docs/dem.md).
  if (spec.rows < 3 || spec.rows % 2 == 0 || spec.discs_per_row < 3 || !(spec.radius > 0.0) || !gauges_fit) {
    throw std::invalid_argument("hex assembly needs an odd number (>= 3) of rows; " + std::to_string(spec.rows) +
                                " rows x " + std::to_string(spec.discs_per_row) + " discs with gauges of " +
                                std::to_string(spec.gauge_columns) + " columns and " +
                                std::to_string(spec.gauge_row_pairs) + " row pairs does not fit");
  }
}

// For kT >= 0 the matrix is symmetric positive definite. For kT < 0 (the range Fig. 7 of Abe 1996
// also explores) it is indefinite, since a disc turning alone then lowers the energy; LDL^T without
// pivoting usually still works there, and LU with pivoting takes over when it does not. Near
// kT/kN = -1/3 the lattice has a nearly free mode (docs/dem.md) and no factorisation helps.
Eigen::VectorXd solve_stiffness(const Eigen::SparseMatrix<double>& stiffness, const Eigen::VectorXd& load,
                                double stiffness_ratio) {
  constexpr double kResidualTolerance = 1e-8;
  // An unknown without stiffness of its own (no springs at all) makes the matrix structurally
  // singular; SparseLU is not meant for that case, so it is caught here.
  if ((stiffness.diagonal().array() == 0.0).any()) {
    throw std::runtime_error("hex assembly stiffness matrix is singular for kT/kN = " +
                             number_text(stiffness_ratio) + ": an unknown has no stiffness");
  }
  const auto relative_residual = [&](const Eigen::VectorXd& x) {
    return (stiffness * x - load).norm() / load.norm();
  };
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> cholesky(stiffness);
  if (cholesky.info() == Eigen::Success) {
    Eigen::VectorXd x = cholesky.solve(load);
    if (relative_residual(x) < kResidualTolerance) return x;
  }
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  lu.compute(stiffness);
  if (lu.info() == Eigen::Success) {
    Eigen::VectorXd x = lu.solve(load);
    if (relative_residual(x) < kResidualTolerance) return x;
  }
  throw std::runtime_error(
      "hex assembly stiffness matrix is singular for kT/kN = " + number_text(stiffness_ratio));
}

}  // namespace

HexAssemblyResult analyse_hex_assembly(const HexAssemblySpec& spec) {
  check_spec(spec);
  const double a = spec.radius;
  // With kT = 0 nothing resists or is driven by a disc's rotation, so it is left out of the system.
  const bool with_rotation = !spec.rotations_locked && spec.springs.tangential != 0.0;
  const DofMap dofs(spec, with_rotation);
  const auto pairs = touching_pairs(spec);

  // Contact stiffness from the energy 1/2 kN dn^2 + 1/2 kT dt^2 with dn = (u_B - u_A).n and
  // dt = (u_B - u_A).s - (w_A + w_B) (Abe 1996, eq. 1-3).
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(pairs.size() * 72);
  for (const auto& [disc_a, disc_b] : pairs) {
    const Vec2 n = (centre_of(disc_b, a) - centre_of(disc_a, a)) / (2.0 * a);
    const Vec2 s = tangent_of(n);
    const std::array<int, 6> index{dofs(disc_a, 0), dofs(disc_a, 1), with_rotation ? dofs(disc_a, 2) : kFixed,
                                   dofs(disc_b, 0), dofs(disc_b, 1), with_rotation ? dofs(disc_b, 2) : kFixed};
    const std::array<double, 6> normal_row{-n.x(), -n.y(), 0.0, n.x(), n.y(), 0.0};
    const std::array<double, 6> tangent_row{-s.x(), -s.y(), -1.0, s.x(), s.y(), -1.0};
    for (int i = 0; i < 6; ++i) {
      if (index[i] == kFixed) continue;
      for (int j = 0; j < 6; ++j) {
        if (index[j] == kFixed) continue;
        const double k = spec.springs.normal * normal_row[i] * normal_row[j] +
                         spec.springs.tangential * tangent_row[i] * tangent_row[j];
        if (k != 0.0) triplets.emplace_back(index[i], index[j], k);
      }
    }
  }
  Eigen::SparseMatrix<double> stiffness(dofs.count(), dofs.count());
  stiffness.setFromTriplets(triplets.begin(), triplets.end());

  Eigen::VectorXd load = Eigen::VectorXd::Zero(dofs.count());
  const auto add_load = [&](DiscId disc, int component, double value) {
    const int i = dofs(disc, component);
    if (i != kFixed) load[i] += value;  // a supported component passes its load to the support
  };
  if (spec.loading == HexLoading::equal_end_forces) {
    // Abe 1996, §3: each row carries a band sqrt3 a high of the applied stress.
    const double end_force = spec.applied_stress * std::numbers::sqrt3 * a;
    for (int row = 0; row < spec.rows; ++row) {
      add_load({row, 0}, 0, -end_force);
      add_load({row, discs_in_row(spec, row) - 1}, 0, end_force);
    }
  } else {
    const Mat2 gradient = uniaxial_plane_strain_gradient(spec.springs, spec.applied_stress);
    for (const auto& [disc, missing] : missing_neighbours(spec, pairs)) {
      for (const Vec2& n : missing) {
        // What the absent neighbour would exert in the uniform state, in which no disc turns.
        const ContactLoad contact = contact_load(spec.springs, n, 2.0 * a * gradient * n, 0.0, 0.0, a);
        add_load(disc, 0, contact.force.x());
        add_load(disc, 1, contact.force.y());
        if (with_rotation) add_load(disc, 2, contact.moment / a);  // w = a theta is work-conjugate to M / a
      }
    }
  }

  const Eigen::VectorXd solution = solve_stiffness(stiffness, load, spec.springs.tangential_to_normal());

  const auto displacement = [&](DiscId disc) -> Vec2 {
    Vec2 u = Vec2::Zero();
    for (int c = 0; c < 2; ++c) {
      const int i = dofs(disc, c);
      if (i != kFixed) u[c] = solution[i];
    }
    return u;
  };
  const auto rotation = [&](DiscId disc) -> double {
    return with_rotation ? solution[dofs(disc, 2)] / a : 0.0;
  };

  HexAssemblyResult result;
  result.unknowns = dofs.count();
  const int middle_row = spec.rows / 2;
  const int middle_column = discs_in_row(spec, middle_row) / 2;
  const DiscId gauge_a{middle_row, middle_column - spec.gauge_columns};
  const DiscId gauge_b{middle_row, middle_column + spec.gauge_columns};
  const DiscId gauge_c{middle_row - 2 * spec.gauge_row_pairs, middle_column};
  const DiscId gauge_d{middle_row + 2 * spec.gauge_row_pairs, middle_column};
  result.strain_11 = (displacement(gauge_b).x() - displacement(gauge_a).x()) /
                     (centre_of(gauge_b, a).x() - centre_of(gauge_a, a).x());
  result.strain_22 = (displacement(gauge_d).y() - displacement(gauge_c).y()) /
                     (centre_of(gauge_d, a).y() - centre_of(gauge_c, a).y());
  result.poisson_ratio = -result.strain_22 / (result.strain_11 - result.strain_22);  // Abe 1996, eq. 35
  result.stiffness_ratio = spec.applied_stress / (spec.springs.normal * result.strain_11);  // Abe 1996, eq. 36

  // The middle disc: its contact forces give the eq. 50 stress; its neighbours give the local strain.
  const DiscId centre{middle_row, middle_column};
  const Vec2 centre_position = centre_of(centre, a);
  std::vector<ContactForce> contacts;
  Mat2 moment_of_branches = Mat2::Zero();  // sum d d^T
  Mat2 displacement_times_branch = Mat2::Zero();  // sum du d^T
  for (const auto& [disc_a, disc_b] : pairs) {
    const bool touches_a = disc_a.row == centre.row && disc_a.column == centre.column;
    const bool touches_b = disc_b.row == centre.row && disc_b.column == centre.column;
    if (!touches_a && !touches_b) continue;
    const DiscId other = touches_a ? disc_b : disc_a;
    const Vec2 branch = centre_of(other, a) - centre_position;
    const Vec2 n = branch.normalized();
    const Vec2 relative = displacement(other) - displacement(centre);
    const ContactLoad contact = contact_load(spec.springs, n, relative, rotation(centre), rotation(other), a);
    contacts.push_back({contact.force, n});
    moment_of_branches += branch * branch.transpose();
    displacement_times_branch += relative * branch.transpose();
  }
  result.centre_stress = disc_contact_stress(contacts, a, kHexagonalDensityRatio);
  const Mat2 gradient = displacement_times_branch * moment_of_branches.inverse();
  result.centre_strain = 0.5 * (gradient + gradient.transpose());
  result.centre_rotation = rotation(centre);
  return result;
}

}  // namespace talus::dem
