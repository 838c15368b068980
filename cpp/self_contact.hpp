#pragma once
/// @brief Self-collision of the lattice (docs/dynamics.md §3.3; issue #12 item 6): keeps every
/// couple's mid-point at least a separation away from the mid-surface triangles of the couples
/// that are not its topological neighbours, so that the layers between couples, and the mesh
/// embedded in them, never pass through each other.
///
/// After each substep, as for collision objects: candidate pairs (a moving couple's mid-point,
/// a triangle of the control surface near it) come from a spatial hash of the moving couples'
/// mid-points, kept while no couple has moved by half a margin since (so a sheet far from
/// itself pays one check of its moving couples' travel per substep); each pair closer than the
/// separation is pushed apart along the triangle's
/// normal, to the side the point was on after the previous projection, sharing the push by
/// inverse mass (a resting or pinned couple does not move), and the approach along the normal
/// is removed from the pair's relative velocity (inelastic). Both vertices of a couple take the
/// same correction, so a couple keeps its thickness. Nothing moving: no work at all.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "lattice.hpp"
#include "point_grid.hpp"

namespace thinburn {

class SelfContact {
 public:
  /// @brief The triangles of the lattice's mid-surface: two per quad of an M x M grid
  /// (topology.grid_side > 0), else the triangles of the couples' neighbour graph (a control
  /// surface's triangulation). rest: (2 couples) x 3 rest positions (2 c + 1 the top).
  SelfContact(const LatticeTopology& topology, const RowMatX3& rest);

  /// @brief Separation (m) of `factor` lattice thicknesses (the couples' mean rest
  /// top-bottom distance): with factor 1, two layers touch and do not overlap.
  double separation(double factor) const { return factor * thickness_; }

  /// @brief Push apart every pair closer than `separation` (m) and remove its approaching
  /// normal velocity. x, v: (2 couples) x 3 positions and velocities; mass: per vertex (kg);
  /// slot: per vertex, >= 0 when it moves this substep. Returns the pairs in contact.
  int apply(double separation, RowMatX3& x, RowMatX3& v, const Eigen::VectorXd& mass,
            const std::vector<int>& slot);

  /// @brief Forget the side each pair was on and the candidate pairs (positions were set from
  /// outside): the next apply starts from the positions it is given.
  void reset() {
    last_.resize(0, 3);
    broad_.resize(0, 3);
  }

  /// @brief Mid-surface triangles, (triangles) x 3 couple indices.
  const std::vector<Eigen::Vector3i>& triangles() const { return tri_; }

 private:
  struct Pair {
    int point, tri;
    double b[3];   // barycentric weights of the point's projection on the triangle
    double side;   // +1 / -1: the side of the triangle's normal the point must stay on
  };
  bool neighbours(int c, const Eigen::Vector3i& t) const;
  bool broad_valid(double sep, const RowMatX3& x) const;
  void broad_phase(double sep, const RowMatX3& x);
  void narrow_phase(double sep, const RowMatX3& x, const RowMatX3& v, const Eigen::VectorXd& mass);
  void project();
  void stop_approach();

  int C_ = 0;
  double thickness_ = 0.0;
  double cell_ = 0.0;                        // hash cell edge, m: the rest spacing between couples
  std::vector<Eigen::Vector3i> tri_;
  std::vector<int> ring_start_, ring_;       // per couple: couples within kRings rings, sorted
  RowMatX3 rest_mid_;                        // mid-points at rest
  RowMatX3 last_;                            // mid-points after the previous apply (sides)
  RowMatX3 broad_;                           // mid-points when the candidates were found (0 rows: none)
  double broad_sep_ = 0.0;                   // the separation they were found for
  std::vector<std::uint8_t> broad_moving_;   // per couple: it moved when they were found
  std::vector<std::pair<int, int>> candidates_;  // (couple, triangle) that may come within the separation
  // Per apply (reused buffers).
  RowMatX3 mid_, vmid_;                      // per couple, valid for the couples in involved_
  Eigen::VectorXd inv_;                      // per couple: inverse mass, 0 when it does not move
  std::vector<int> moving_, involved_;
  std::vector<std::uint8_t> is_involved_;
  PointGrid grid_;                           // the moving couples' mid-points, for broad_phase
  std::vector<Pair> pairs_;
  double sep_ = 0.0;                         // the separation of the apply in progress
};

}  // namespace thinburn
