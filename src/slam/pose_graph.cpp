#include "rgbdmap/slam/pose_graph.hpp"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>

namespace rgbdmap {
namespace {

template <typename T>
Eigen::Matrix<T, 6, 1> edgeError(const Eigen::Isometry3d& z, const T* ta, const T* qa, const T* tb,
                                 const T* qb) {
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> pa(ta), pb(tb);
  const Eigen::Map<const Eigen::Quaternion<T>> Qa(qa), Qb(qb);
  const Eigen::Quaternion<T> qa_inv = Qa.conjugate();
  // The estimated relative pose, then the measurement's inverse applied to it.
  const Eigen::Quaternion<T> q_ab = qa_inv * Qb;
  const Eigen::Matrix<T, 3, 1> p_ab = qa_inv * (pb - pa);
  const Eigen::Quaterniond qz(z.linear());
  const Eigen::Quaternion<T> qz_inv = qz.conjugate().cast<T>();
  const Eigen::Quaternion<T> dq = qz_inv * q_ab;
  Eigen::Matrix<T, 6, 1> e;
  e.template head<3>() = qz_inv * (p_ab - z.translation().cast<T>());
  e.template tail<3>() = T(2.0) * dq.vec();
  return e;
}

struct RelativePoseCost {
  Eigen::Isometry3d measurement;
  Eigen::Matrix<double, 6, 6> sqrt_information;

  template <typename T>
  bool operator()(const T* ta, const T* qa, const T* tb, const T* qb, T* residual) const {
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r = sqrt_information.cast<T>() * edgeError(measurement, ta, qa, tb, qb);
    return true;
  }
};

// The world plane as the node's camera would see it, against what it saw.
struct PlaneCost {
  Eigen::Vector3d world_normal;
  double world_distance;
  Eigen::Vector3d normal;
  double distance;
  double normal_weight, distance_weight;

  template <typename T>
  bool operator()(const T* t, const T* q, T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> position(t);
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(q);
    const Eigen::Matrix<T, 3, 1> n = world_normal.cast<T>();
    const Eigen::Matrix<T, 3, 1> predicted = rotation.conjugate() * n;
    for (int i = 0; i < 3; ++i) residual[i] = T(normal_weight) * (predicted[i] - T(normal[i]));
    residual[3] = T(distance_weight) * (T(world_distance) - n.dot(position) - T(distance));
    return true;
  }
};

}  // namespace

void PoseGraph::setWorldPlane(const Eigen::Vector3d& normal, double distance) {
  world_normal_ = normal.normalized();
  world_distance_ = distance;
  has_world_plane_ = true;
}

void PoseGraph::addPlaneObservation(const PlaneObservation& observation) {
  planes_.push_back(observation);
}

int PoseGraph::addNode(const Eigen::Isometry3d& estimate) {
  nodes_.emplace_back();
  setPose(size() - 1, estimate);
  return size() - 1;
}

void PoseGraph::setPose(int node, const Eigen::Isometry3d& estimate) {
  Node& n = nodes_[static_cast<std::size_t>(node)];
  const Eigen::Quaterniond q(estimate.linear());
  const Eigen::Vector3d t = estimate.translation();
  for (int i = 0; i < 3; ++i) n.t[i] = t[i];
  n.q[0] = q.x();
  n.q[1] = q.y();
  n.q[2] = q.z();
  n.q[3] = q.w();
}

void PoseGraph::hold(int node, bool held) {
  held_.erase(std::remove(held_.begin(), held_.end(), node), held_.end());
  if (held) held_.push_back(node);
}

void PoseGraph::addEdge(const Edge& edge) { edges_.push_back(edge); }

PoseGraph::Checkpoint PoseGraph::checkpoint(int first_free) const {
  Checkpoint c;
  c.edges = edges_.size();
  c.planes = planes_.size();
  c.first_free = std::clamp(first_free, 0, size());
  c.nodes.assign(nodes_.begin() + c.first_free, nodes_.end());
  return c;
}

void PoseGraph::rollBack(const Checkpoint& c) {
  edges_.resize(std::min(c.edges, edges_.size()));
  planes_.resize(std::min(c.planes, planes_.size()));
  std::copy(c.nodes.begin(), c.nodes.end(), nodes_.begin() + c.first_free);
}

void PoseGraph::removeLastEdges(std::size_t count) {
  edges_.resize(edges_.size() - std::min(count, edges_.size()));
}

Eigen::Isometry3d PoseGraph::pose(int node) const {
  const Node& n = nodes_[static_cast<std::size_t>(node)];
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(n.q[3], n.q[0], n.q[1], n.q[2]).normalized().toRotationMatrix();
  out.translation() = Eigen::Vector3d(n.t[0], n.t[1], n.t[2]);
  return out;
}

double PoseGraph::whitenedError(const Edge& edge) const {
  const Node& a = nodes_[static_cast<std::size_t>(edge.from)];
  const Node& b = nodes_[static_cast<std::size_t>(edge.to)];
  return (edge.sqrtInformation() * edgeError(edge.measurement(), a.t, a.q, b.t, b.q)).norm();
}

double PoseGraph::worstWhitenedError(std::size_t count) const {
  double worst = 0.0;
  for (std::size_t i = edges_.size() - std::min(count, edges_.size()); i < edges_.size(); ++i)
    worst = std::max(worst, whitenedError(edges_[i]));
  return worst;
}

PoseGraph::Matrix6d PoseGraph::sqrtInformation(const Matrix6d& information) {
  const Matrix6d symmetric = 0.5 * (information + information.transpose());
  Eigen::SelfAdjointEigenSolver<Matrix6d> eig(symmetric);
  Eigen::Matrix<double, 6, 1> values = eig.eigenvalues();
  const double floor = std::max(1e-9, 1e-6 * values.maxCoeff());
  for (int i = 0; i < 6; ++i) values[i] = std::max(values[i], floor);
  const Matrix6d floored =
      eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
  return Matrix6d((0.5 * (floored + floored.transpose())).llt().matrixU());
}

Eigen::Isometry3d PoseGraph::Edge::measurement() const {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.matrix().topRows<3>() = measurement_;
  return out;
}

void PoseGraph::Edge::setMeasurement(const Eigen::Isometry3d& measurement) {
  measurement_ = measurement.matrix().topRows<3>();
}

PoseGraph::Matrix6d PoseGraph::Edge::sqrtInformation() const {
  Matrix6d out = Matrix6d::Zero();
  std::size_t k = 0;
  for (int r = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c) out(r, c) = sqrt_information_[k++];
  return out;
}

void PoseGraph::Edge::setSqrtInformation(const Matrix6d& sqrt_information) {
  const bool upper =
      sqrt_information.triangularView<Eigen::StrictlyLower>().toDenseMatrix().isZero(0);
  const Matrix6d u =
      upper ? sqrt_information
            : PoseGraph::sqrtInformation(sqrt_information.transpose() * sqrt_information);
  std::size_t k = 0;
  for (int r = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c) sqrt_information_[k++] = static_cast<float>(u(r, c));
}

PoseGraph::Summary PoseGraph::optimise(int max_iterations, int first_free) {
  Summary out;
  if (nodes_.size() < 2 || edges_.empty() || first_free >= static_cast<int>(nodes_.size())) {
    out.usable = true;
    return out;
  }
  const auto start = std::chrono::steady_clock::now();
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion;
  const std::vector<Node> before = nodes_;
  first_free = std::max(first_free, 1);
  for (const Edge& e : edges_) {
    if (e.from < first_free && e.to < first_free) continue;
    Node& a = nodes_[static_cast<std::size_t>(e.from)];
    Node& b = nodes_[static_cast<std::size_t>(e.to)];
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 3, 4, 3, 4>(
        new RelativePoseCost{e.measurement(), e.sqrtInformation()});
    problem.AddResidualBlock(cost, nullptr, a.t, a.q, b.t, b.q);
  }
  for (const PlaneObservation& o : planes_) {
    if (!has_world_plane_ || o.node < first_free) continue;
    Node& n = nodes_[static_cast<std::size_t>(o.node)];
    auto* cost = new ceres::AutoDiffCostFunction<PlaneCost, 4, 3, 4>(new PlaneCost{
        world_normal_, world_distance_,
        Eigen::Vector3f(o.normal[0], o.normal[1], o.normal[2]).cast<double>(),
        static_cast<double>(o.distance), 1.0 / o.sigma_normal, 1.0 / o.sigma_distance});
    problem.AddResidualBlock(cost, nullptr, n.t, n.q);
  }
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    Node& n = nodes_[i];
    if (!problem.HasParameterBlock(n.q)) continue;
    problem.SetManifold(n.q, &quaternion);
    if (static_cast<int>(i) < first_free ||
        std::find(held_.begin(), held_.end(), static_cast<int>(i)) != held_.end()) {
      problem.SetParameterBlockConstant(n.t);
      problem.SetParameterBlockConstant(n.q);
    }
  }

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;  // its own thread already; tracking and fusion have the other core
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  out.iterations = static_cast<int>(summary.iterations.size());
  out.initial_cost = summary.initial_cost;
  out.final_cost = summary.final_cost;
  bool finite = std::isfinite(summary.final_cost);
  for (const Node& n : nodes_)
    for (double v : {n.t[0], n.t[1], n.t[2], n.q[0], n.q[1], n.q[2], n.q[3]})
      finite = finite && std::isfinite(v);
  out.usable = finite && summary.termination_type != ceres::FAILURE;
  if (!out.usable) nodes_ = before;  // keep the last good estimates
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace rgbdmap
