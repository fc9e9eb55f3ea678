#pragma once

#include <Eigen/Geometry>
#include <array>
#include <deque>
#include <vector>

namespace rgbdmap {

// Keyframe poses as nodes, measured relative motions as edges; optimised with Ceres
// (Levenberg-Marquardt, sparse normal Cholesky). Node 0 is held fixed: it defines the world (and
// so does any node held by hold(): the root of a part of the graph not tied to the rest yet).
// An edge's error is log(Z^-1 * X_from^-1 * X_to) with the rotation part approximated by twice
// the vector part of the quaternion, [translation, rotation], whitened by the square root of
// the edge's information.
class PoseGraph {
 public:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  // 208 bytes instead of 432: a patrol adds one or two a keyframe for as long as it runs. The
  // measurement's top three rows; the square root of the information as an upper triangle in
  // floats (a weight: a float's precision is plenty, and the bits read back are the bits
  // written).
  class Edge {
   public:
    int from = 0, to = 0;
    bool loop = false;

    Eigen::Isometry3d measurement() const;  // X_from^-1 * X_to
    void setMeasurement(const Eigen::Isometry3d& measurement);
    // Upper triangular: any square root S of the information (S^T S) is stored as the one
    // with the same S^T S that is (its Cholesky factor).
    Matrix6d sqrtInformation() const;
    void setSqrtInformation(const Matrix6d& sqrt_information);

   private:
    Eigen::Matrix<double, 3, 4> measurement_ = Eigen::Matrix<double, 3, 4>::Identity();
    // Row by row, from the diagonal on; the identity until set.
    std::array<float, 21> sqrt_information_{1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0,
                                            1, 0, 0, 0, 1, 0, 0, 1, 0, 1};
  };
  struct Node {
    double t[3];
    double q[4];  // x y z w (Eigen's order)
  };
  // The world plane (the floor: setWorldPlane()) as a node's camera saw it, n . x = d in the
  // camera's frame: ties the node's tilt and height to the plane, which no chain of relative
  // motions does (their small errors add up into a floor that climbs or tilts).
  struct PlaneObservation {
    int node = 0;
    float normal[3] = {0, 0, 0};
    float distance = 0;
    float sigma_normal = 1e-3f;    // rad
    float sigma_distance = 2e-3f;  // m
  };
  // Enough to undo a tentative change (edges added, then optimise(.., first_free)): the edge
  // count and the estimates of the nodes from first_free on. A copy of the whole graph would
  // cost as much as the graph, which grows with every keyframe.
  struct Checkpoint {
    std::size_t edges = 0;
    std::size_t planes = 0;
    int first_free = 0;
    std::vector<Node> nodes;
  };
  struct Summary {
    bool usable = false;  // the solver ended with a finite solution
    int iterations = 0;
    double seconds = 0.0;
    double initial_cost = 0.0, final_cost = 0.0;
  };

  int addNode(const Eigen::Isometry3d& estimate);  // returns the node's index
  void setPose(int node, const Eigen::Isometry3d& estimate);
  // Holds a node fixed in optimise() (or lets it go again).
  void hold(int node, bool held);
  void addEdge(const Edge& edge);
  void removeLastEdges(std::size_t count);  // undoes the last `count` addEdge calls
  // The world's plane (n . x = d, n unit, in the world frame) that plane observations see; it is
  // held where it is set (by the first observation, where the graph had its camera then).
  void setWorldPlane(const Eigen::Vector3d& normal, double distance);
  bool hasWorldPlane() const { return has_world_plane_; }
  Eigen::Vector3d worldPlaneNormal() const { return world_normal_; }
  double worldPlaneDistance() const { return world_distance_; }
  void addPlaneObservation(const PlaneObservation& observation);
  const std::vector<PlaneObservation>& planeObservations() const { return planes_; }
  Checkpoint checkpoint(int first_free) const;
  void rollBack(const Checkpoint& checkpoint);  // no node may have been added since

  // Optimises the nodes from `first_free` on; the older ones (and node 0 always) are held where
  // they are, and edges between two of them are left out (they cannot change anything).
  Summary optimise(int max_iterations = 100, int first_free = 0);

  int size() const { return static_cast<int>(nodes_.size()); }
  Eigen::Isometry3d pose(int node) const;
  // A deque: growing it never copies the edges already there (a long run has tens of thousands).
  const std::deque<Edge>& edges() const { return edges_; }
  // |whitened error| of an edge at the current estimates.
  double whitenedError(const Edge& edge) const;
  // The largest of the last `count` edges' (loops just added: does the graph agree with them?).
  double worstWhitenedError(std::size_t count) const;

  // Square root of an information matrix, upper triangular (symmetrised, with a small floor on
  // its eigenvalues so a direction the measurement says nothing about does not make the problem
  // singular).
  static Matrix6d sqrtInformation(const Matrix6d& information);

 private:
  std::vector<Node> nodes_;
  std::deque<Edge> edges_;
  std::vector<int> held_;
  bool has_world_plane_ = false;
  Eigen::Vector3d world_normal_ = Eigen::Vector3d::UnitZ();
  double world_distance_ = 0.0;
  std::vector<PlaneObservation> planes_;  // 28 bytes a keyframe that saw the floor
};

}  // namespace rgbdmap
