#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {
namespace {
const Eigen::Isometry3d kIdentity = Eigen::Isometry3d::Identity();
}  // namespace

const Eigen::Isometry3d& PoseCorrections::Snapshot::of(std::int64_t anchor) const {
  if (anchor < 0 || !table) return kIdentity;
  const auto i = static_cast<std::size_t>(anchor);
  if (i < table->size()) return (*table)[i];
  return static_cast<std::int64_t>(table->size()) > first_own ? table->back() : kIdentity;
}

PoseCorrections::PoseCorrections() { current_.table = std::make_shared<const Table>(); }

void PoseCorrections::publish(Table table, std::int64_t first_own, bool joined) {
  auto shared = std::make_shared<const Table>(std::move(table));
  std::lock_guard<std::mutex> lock(mutex_);
  current_.table = std::move(shared);
  current_.first_own = first_own;
  current_.joined = joined;
  ++current_.version;
}

PoseCorrections::Snapshot PoseCorrections::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return current_;
}

std::uint64_t PoseCorrections::version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return current_.version;
}

}  // namespace rgbdmap
