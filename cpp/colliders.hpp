#pragma once
/// @brief Collision objects for the lattice's motion (docs/dynamics.md §3.2): spheres, oriented
/// boxes and closed triangle meshes, each answering "signed distance and outward normal at a
/// point". A mesh is turned into a signed distance field sampled on a grid when it is added
/// (exact point-triangle distances near the surface, propagated by fast sweeping; sign by ray
/// parity along the grid's x lines) and read back by trilinear interpolation.
///
/// Every collider has a pose, world = rotation * local + translation, that may change between
/// steps (set_transform); each change bumps version(), which wakes a sleeping sheet.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace thinburn {

/// @brief Closest point to p on triangle abc (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// @brief The nearest collider's answer at a point.
struct ColliderHit {
  double distance = 0.0;          ///< m, signed: < 0 inside (to the surface grown by thickness)
  Eigen::Vector3d normal{0, 0, 1};  ///< outward unit normal (world)
  double friction = 0.0;          ///< its Coulomb coefficient
  int index = -1;                 ///< which collider, -1 when there is none
};

class Colliders {
 public:
  using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  using RowMatX3i = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

  /// @brief A sphere (radius > 0). friction: Coulomb coefficient >= 0; thickness >= 0 grows the
  /// surface outward (Blender's outer thickness). Returns its index.
  int add_sphere(const Eigen::Vector3d& centre, double radius, double friction, double thickness);
  /// @brief A box: half_extents > 0 along the columns of rotation (orthonormal, det +1).
  int add_box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half_extents,
              const Eigen::Matrix3d& rotation, double friction, double thickness);
  /// @brief A closed triangle mesh (every edge shared by exactly two faces), its vertices in its
  /// local frame (pose: identity); resolution: grid cells along its longest side, 8..512.
  int add_mesh(const RowMatX3& vertices, const RowMatX3i& faces, double friction, double thickness,
               int resolution);
  /// @brief Replace collider i's pose: world = rotation * local + translation (a sphere's or a
  /// box's local centre is the origin).
  void set_transform(int i, const Eigen::Vector3d& translation, const Eigen::Matrix3d& rotation);
  void set_friction(int i, double friction);

  int size() const { return static_cast<int>(shapes_.size()); }
  bool empty() const { return shapes_.empty(); }
  /// @brief Bumped by every change (add, pose, friction).
  std::uint64_t version() const { return version_; }
  /// @brief The nearest (smallest signed distance) collider at a world point.
  ColliderHit query(const Eigen::Vector3d& p) const;
  /// @brief Collider i alone at a world point.
  ColliderHit query_one(int i, const Eigen::Vector3d& p) const;
  /// @brief Collider i's pose: world = rotation(i) * local + translation(i).
  const Eigen::Vector3d& translation(int i) const { return shapes_.at(i).t; }
  const Eigen::Matrix3d& rotation(int i) const { return shapes_.at(i).R; }
  /// @brief Mesh collider i's grid spacing (m, local frame); 0 for a sphere or a box.
  double grid_spacing(int i) const;
  /// @brief "sphere", "box" or "mesh".
  const char* kind(int i) const;

 private:
  enum class Kind { Sphere, Box, Mesh };
  struct Grid {
    Eigen::Vector3d origin;
    double dx = 0.0;
    int n[3] = {0, 0, 0};
    std::vector<double> phi;  // x fastest
    double at(int i, int j, int k) const { return phi[(std::size_t(k) * n[1] + j) * n[0] + i]; }
  };
  struct Shape {
    Kind kind;
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    double radius = 0.0;      // sphere
    Eigen::Vector3d half{0, 0, 0};  // box
    int grid = -1;            // mesh: index into grids_
    double friction = 0.0, thickness = 0.0;
  };
  int add(Shape s);
  void check_index(int i, const char* what) const;
  double local_distance(const Shape& s, const Eigen::Vector3d& q, Eigen::Vector3d& n) const;
  static double grid_distance(const Grid& g, const Eigen::Vector3d& q, Eigen::Vector3d& n);

  std::vector<Shape> shapes_;
  std::vector<Grid> grids_;
  std::uint64_t version_ = 0;
};

/// @brief The colliders' velocities during a step. A collider is moved by set_transform between
/// steps (Blender's animation: once a frame); the step that follows reads the pose change as a
/// rigid motion at constant velocity over its dt, so a contact can take the collider's speed,
/// not only its position (docs/dynamics.md §3.2).
class ColliderMotion {
 public:
  /// @brief A step of dt starts: each collider's motion since the last call over dt (none for a
  /// collider this object has not seen before, or whose pose is bitwise the same).
  void update(const Colliders& colliders, double dt);
  /// @brief Forget the poses: the next update sees no motion.
  void clear() { last_.clear(); }
  /// @brief Velocity (m/s) during this step of the point of collider i at world p.
  Eigen::Vector3d velocity(int i, const Eigen::Vector3d& p) const;

 private:
  struct Pose {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
  };
  std::vector<Pose> last_, before_;  // the poses at the last update, and at the one before it
  std::vector<std::uint8_t> moving_;  // per collider: its pose changed at the last update
  double dt_ = 0.0;
};

}  // namespace thinburn
