#pragma once
/// @brief Creases of a shell's mesh: edges where the surface turns sharply (a folded letter's
/// fold, a paper box's edges), and the sides they cut it into (docs/lattice.md, "Creases").
///
/// A crease is a hinge: the two sides turn about it independently, and a smooth embedding that
/// mixes the couples of both sides cannot follow that without stretching the sheet across it.
/// The control surface therefore puts couples on the creases (as on the rim) and embeds a point
/// with the couples of its own side only (and those on the crease).
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace thinburn {

struct Creases {
  std::vector<std::uint8_t> vertex;  ///< per vertex: 1 on a crease edge
  std::vector<std::uint8_t> sliver;  ///< per vertex: 1 on a sliver joined to a side (join_slivers)
  std::vector<int> face_side;        ///< per face: its side (faces joined across non-crease edges)
  int sides = 0;                     ///< number of sides (0: the mesh has no crease edge)
  int edges = 0;                     ///< number of crease edges
  std::vector<int> ends;             ///< crease vertices on the boundary or where creases meet or stop
};

/// @brief The creases of a consistently oriented triangle mesh: interior edges whose two faces'
/// normals differ by more than `angle` (rad). Where no edge qualifies, `sides` is 0 and
/// `face_side` empty. A crease's ends are the vertices where it meets the boundary, stops, or
/// meets another crease (not two crease edges, or one on a boundary edge).
Creases find_creases(const std::vector<Eigen::Vector3d>& vertices, const std::vector<std::array<int, 3>>& faces,
                     double angle);

}  // namespace thinburn
