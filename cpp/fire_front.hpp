#pragma once
/// @brief The fire front on the sheet's cell grid (paper §3, eq 1): arrival (ignition) times.
///
/// Four methods share one event loop: the paper's neighbour rule (Dijkstra on an 8- or
/// 16-neighbour stencil) and fast marching for the eikonal equation F|grad T| = 1 (first or
/// second order). Single-threaded: the loop is a priority queue. Grid: ny rows by nx columns, cell = row*nx + col, cell centres at integer
/// (row, col), spacing dy between rows and dx between columns (metres).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

namespace thinburn {

using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief How the front moves from cell to cell.
/// Cellular8: the paper's rule (8 neighbours), Dijkstra; octagonal fronts, up to 8.24 % late.
/// Cellular16: the same with knight moves added; up to 2.75 % late.
/// Fmm1: first-order fast marching. Fmm2: second-order fast marching, factored at the
/// sources (T = t0 + T0 tau): exact for uniform speed and drive, second order in smooth
/// isotropic media, first order with a drive. With a drive (|e| > 0) both fast-marching
/// methods use a Huygens update on the 8-neighbour ring; keep |e| <= 0.7.
enum class FrontMethod { Cellular8, Cellular16, Fmm1, Fmm2 };

/// @brief Local spread speed of a cell.
/// v > 0 (m/s); v <= 0 means the cell cannot burn now. (e_row, e_col) is a drive vector in
/// grid axes, |e| < 1, zero for isotropic spread. The spread shape is the focus-at-origin
/// ellipse: ray speed in unit direction u is v*(1-|e|^2)/(1 - e.u) (head v(1+|e|), back
/// v(1-|e|)); normal speed F(n) = v*(e.n + sqrt(1-|e|^2+(e.n)^2)).
struct LocalSpeed {
  double v;
  double e_row = 0.0;
  double e_col = 0.0;
};

/// @brief Speed law: cell index (row*nx + col) -> its local speed.
using SpeedFn = std::function<LocalSpeed(int cell)>;

/// @brief A point source at fractional grid coordinates (cell centres at integers), lit at t0.
struct FrontSource {
  double row, col, t0;
};

/// @brief Settings of the fast-marching methods; the defaults are the measured best
/// (docs/fire_front.md), the others exist to reproduce the comparisons there.
struct FrontOptions {
  /// Cells within this distance (in cells) of a point source get exact times
  /// t0 + distance / ray speed of the source cell. >= 0; 0 = only the nearest cell.
  double init_radius = 1.0;
  /// Fmm2 only: solve for tau in T = t0 + T0 tau, T0 the uniform-medium travel time from the
  /// source (exact for uniform speed and drive; second order elsewhere).
  bool factored = true;
  /// Cells with a drive (|e| > 0): Huygens update on the 8-neighbour ring (true) or the
  /// Eulerian 4-neighbour quadratic for h(grad T) = 1 (false; not causal for |e| > 0).
  bool huygens = true;
};

/// @brief Incremental fire-front solver: ignite sources, then advance in time.
///
/// Cells are accepted (ignited) in order of arrival time, ties broken by cell index, so the
/// result does not depend on how the time axis is cut into advance() calls.
class FireFront {
 public:
  /// @brief An empty front on an ny x nx grid with spacings dy (rows) and dx (columns) in metres.
  FireFront(int ny, int nx, double dy, double dx, FrontMethod method,
            const FrontOptions& options = FrontOptions());

  /// @brief Cells with inside==0 never burn (holes, area outside the outline). Default: all inside.
  /// @param inside ny*nx flags, row-major.
  void set_inside(const std::vector<std::uint8_t>& inside);

  /// @brief Ignite a point source at time s.t0 (>= every t_end advanced to so far).
  /// Cellular methods snap it to the nearest cell; fast marching sets exact times
  /// t0 + distance / ray speed (of the source cell) on the cells within
  /// FrontOptions::init_radius of it. A source on a cell that cannot burn does nothing.
  void ignite(const FrontSource& s, const SpeedFn& speed);

  /// @brief Accept, in time order, every cell whose arrival time is <= t_end.
  /// Speeds are asked from `speed` when a neighbour update needs them, so the speed law may
  /// change between calls. @return the cells accepted by this call, in acceptance order.
  const std::vector<int>& advance(double t_end, const SpeedFn& speed);

  /// @brief Accepted arrival times (s), +inf where a cell has not burnt yet.
  const std::vector<double>& arrival() const { return arrival_; }
  /// @brief Whether the cell's arrival time is final.
  bool accepted(int cell) const;
  /// @brief Number of cells in the narrow band (tentative time, not yet accepted).
  std::size_t num_trial() const { return n_trial_; }
  /// @brief Largest t_end advanced to so far (-inf before the first advance).
  double time() const { return t_done_; }
  int ny() const { return ny_; }
  int nx() const { return nx_; }
  FrontMethod method() const { return method_; }

 private:
  struct Entry {
    double t;
    int cell;
  };
  struct Step {
    int dr, dc;
    double length, ur, uc;    // metres; unit direction in metres
    int pass_dr[2], pass_dc[2];  // cells the edge passes between or through
    int n_pass;
    bool need_both;           // knight moves cross both cells; diagonals squeeze past
  };
  struct AxisCand {
    double a;      // upwind value of the difference (u - a) * c, u the unknown
    double c;      // alpha / h (alpha = 1 first order, 3/2 second order)
    double sigma;  // +1 when the upwind neighbour has the lower index
    double t1;     // arrival time of the upwind neighbour
  };
  struct SourceRec {
    double row, col, t0;
    LocalSpeed s;  // speed of the source cell at ignition: shapes the factor T0
  };
  struct Solution {
    double t, tau;
    int label;
  };

  bool cellular() const { return method_ == FrontMethod::Cellular8 || method_ == FrontMethod::Cellular16; }
  void push(int cell, double t, double tau, int label);
  void accept(int cell, double t);
  void relax_cellular(int cell, const SpeedFn& speed);
  void update_fmm_neighbours(int cell, const SpeedFn& speed);
  int earliest_label(int r, int c, int ring) const;
  Solution solve_eikonal(int cell, const LocalSpeed& s) const;
  Solution solve_huygens(int cell, const LocalSpeed& s, const SpeedFn& speed) const;
  bool can_burn(int cell, const SpeedFn& speed) const;
  double huygens_factored(int label, int na, int nd, double a, double b, double d0r, double d0c,
                          double qr, double qc, double vw, const LocalSpeed& s, double lam) const;
  int axis_candidates(int r, int c, int axis, bool all, int label, bool second,
                      AxisCand* out) const;
  double factor(int label, int cell, double* g_row, double* g_col) const;
  void factor_minimum(int label, int cell, double T0, bool out[2]) const;
  double unknown_of(int cell, int label) const;
  void ignite_fmm(const FrontSource& s, int cell, const LocalSpeed& src, const SpeedFn& speed);

  int ny_, nx_;
  double dy_, dx_;
  FrontMethod method_;
  FrontOptions opt_;
  std::vector<std::uint8_t> inside_;
  std::vector<std::uint8_t> state_;  // 0 far, 1 trial, 2 accepted
  std::vector<std::uint8_t> fixed_;  // tentative time set exactly from a point source
  std::vector<double> tent_, arrival_;
  std::vector<double> tau_;   // Fmm2: the factored unknown T = t0 + T0 * tau of tent_
  std::vector<int> label_;    // Fmm2: the source whose factor T0 tau_ refers to, -1 none
  std::vector<SourceRec> sources_;
  std::vector<Entry> heap_;
  std::vector<int> accepted_now_;
  std::vector<Step> steps_;
  std::vector<int> flood_, stamp_;
  int stamp_id_ = 0;
  std::size_t n_trial_ = 0;
  double t_done_;
};

/// @brief One-shot arrival times from all sources (advance to +inf), via FireFront.
/// @param speed ny*nx row-major spread speeds >= 0 (m/s); 0 marks a cell that never burns.
/// @param e_row, e_col empty (isotropic) or ny*nx drive components, |e| < 1.
/// @return ny*nx arrival times (s), +inf where unreachable.
std::vector<double> arrival_times(int ny, int nx, const std::vector<double>& speed,
                                  const std::vector<double>& e_row,
                                  const std::vector<double>& e_col,
                                  const std::vector<FrontSource>& sources, double dy, double dx,
                                  FrontMethod method);

/// @brief Ray speed of the drive ellipse in unit direction (ur, uc): v(1-|e|^2)/(1-e.u).
double ray_speed(const LocalSpeed& s, double ur, double uc);
/// @brief Normal speed (support function) of the drive ellipse for unit normal (nr, nc).
double normal_speed(const LocalSpeed& s, double nr, double nc);

}  // namespace thinburn
