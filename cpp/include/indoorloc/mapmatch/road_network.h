// Road network of straight segments with connectivity at their ends (paper 000, §II.B: "a set of
// linear segments identified by their identity index, the coordinates of their ends and their
// direction β").
//
// A vehicle on segment s travels either forward (from end A to end B, heading β_s) or backward
// (B to A, heading β_s + π). When it reaches an end it may continue onto any segment whose end
// coincides with it (within the snap tolerance), entering at that end; turning back onto the
// same segment is allowed only at a dead end. Connectivity is built from the geometry; with
// `split_at_intersections`, segments are first split where they cross or where an end of one
// lies on the interior of another (T-junctions), so that turns are possible there.
//
// Nearest-segment queries use a uniform grid over the bounding box (a spatial index: each cell
// lists the segments passing near it), not a scan over all segments.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace indoorloc::mapmatch {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// One way of leaving a segment end: onto `segment`, entering at its end `enter_end`
/// (0 = A: then travelling forward, 1 = B: travelling backward).
struct Continuation {
  int segment;
  int enter_end;
};

/// Result of a projection onto the network.
struct Projection {
  int segment = -1;                  ///< index (not id) of the nearest segment
  double along_m = 0.0;              ///< distance from end A along the segment [m]
  Eigen::Vector2d point_m = Eigen::Vector2d::Zero();
  double distance_m = 0.0;           ///< distance from the query to point_m [m]
};

struct RoadNetworkOptions {
  /// Segment ends closer than this are the same junction [m].
  double snap_tolerance_m = 1e-6;
  /// Split segments at crossings and T-junctions before building connectivity.
  bool split_at_intersections = false;

  bool IsValid(std::string* error) const;
};

class RoadNetwork {
 public:
  /// segments_m (M x 4): x_A, y_A, x_B, y_B [m]; ids (M) unique (empty: 1..M). Throws
  /// std::invalid_argument on an empty network, NaN, a zero-length segment (naming its id), or
  /// duplicate ids. Dangling ends and disconnected components are allowed but reported.
  RoadNetwork(const Eigen::Ref<const RowMatrixXd>& segments_m, const Eigen::VectorXi& ids,
              const RoadNetworkOptions& options = RoadNetworkOptions());

  int num_segments() const { return static_cast<int>(ends_.rows()); }
  /// Segment ends (M x 4) [m] (after splitting, if requested).
  const RowMatrixXd& segments_m() const { return ends_; }
  /// Segment ids (M); a split segment keeps the id of its original for every piece.
  const Eigen::VectorXi& ids() const { return ids_; }
  /// Direction β of each segment, from A to B [rad], in (-π, π].
  const Eigen::VectorXd& headings_rad() const { return headings_; }
  const Eigen::VectorXd& lengths_m() const { return lengths_; }
  double total_length_m() const { return total_length_; }
  Eigen::Vector2d end_point(int segment, int end) const;
  /// Point at `along_m` from end A of a segment.
  Eigen::Vector2d point_at(int segment, double along_m) const;

  /// Where a vehicle can go when it reaches end `end` (0 = A, 1 = B) of `segment`.
  const std::vector<Continuation>& continuations(int segment, int end) const {
    return continuations_[static_cast<size_t>(2 * segment + end)];
  }
  /// Connected component of each segment (0-based labels); num_components() > 1 means a
  /// disconnected network.
  const Eigen::VectorXi& components() const { return components_; }
  int num_components() const { return num_components_; }
  /// (segment, end) pairs with no continuation other than a U-turn.
  std::vector<std::pair<int, int>> dangling_ends() const;
  /// A human-readable validation report (sizes, components, dangling ends).
  std::string Report() const;

  /// Nearest point of the network to p_m (spatial grid; exact).
  Projection Nearest(const Eigen::Vector2d& p_m) const;
  /// Projection of p_m onto one segment (clamped to its ends).
  Projection ProjectOnto(int segment, const Eigen::Vector2d& p_m) const;

 private:
  void BuildConnectivity(double tolerance);
  void BuildIndex();

  RowMatrixXd ends_;
  Eigen::VectorXi ids_;
  Eigen::VectorXd headings_, lengths_;
  double total_length_ = 0.0;
  std::vector<std::vector<Continuation>> continuations_;
  Eigen::VectorXi components_;
  int num_components_ = 0;
  // Spatial grid.
  double grid_x0_ = 0, grid_y0_ = 0, grid_cell_ = 1;
  int grid_nx_ = 1, grid_ny_ = 1;
  std::vector<std::vector<int>> grid_;
};

}  // namespace indoorloc::mapmatch
