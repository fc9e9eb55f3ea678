#include "rgbdmap/tracking/pose_corrections.hpp"

namespace rgbdmap {
namespace {
const Eigen::Isometry3d kIdentity = Eigen::Isometry3d::Identity();
}  // namespace

const Eigen::Isometry3d& PoseCorrections::Snapshot::of(std::int64_t anchor) const {
  if (anchor < 0 || !table || table->empty()) return kIdentity;
  const auto i = static_cast<std::size_t>(anchor);
  return i < table->size() ? (*table)[i] : table->back();
}

PoseCorrections::PoseCorrections() { current_.table = std::make_shared<const Table>(); }

void PoseCorrections::publish(Table table) {
  auto shared = std::make_shared<const Table>(std::move(table));
  std::lock_guard<std::mutex> lock(mutex_);
  current_.table = std::move(shared);
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
