#include "rgbdmap/mapping/block_store.hpp"

#include <algorithm>
#include <cstring>

namespace rgbdmap {
namespace {

constexpr std::size_t kMaskBytes = BlockStore::kVoxels / 8;

void encode(const BlockStore::Voxels& voxels, std::vector<std::uint8_t>& out) {
  out.assign(kMaskBytes, 0);
  for (int i = 0; i < BlockStore::kVoxels; ++i) {
    if (!voxels[i].observed()) continue;
    out[i / 8] |= static_cast<std::uint8_t>(1u << (i % 8));
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&voxels[i]);
    out.insert(out.end(), bytes, bytes + sizeof(TsdfVoxel));
  }
}

bool decode(const std::vector<std::uint8_t>& in, BlockStore::Voxels& voxels) {
  if (in.size() < kMaskBytes) return false;
  std::size_t at = kMaskBytes;
  for (int i = 0; i < BlockStore::kVoxels; ++i) {
    if ((in[i / 8] >> (i % 8) & 1u) == 0) {
      voxels[i] = TsdfVoxel{};
      continue;
    }
    if (at + sizeof(TsdfVoxel) > in.size()) return false;
    std::memcpy(&voxels[i], in.data() + at, sizeof(TsdfVoxel));
    at += sizeof(TsdfVoxel);
  }
  return at == in.size();
}

}  // namespace

bool BlockStore::put(std::uint64_t key, const Voxels& voxels, std::uint32_t surface_points,
                     std::uint64_t touched_in, std::string& error) {
  if (file_ && file_->bytes() - stored_bytes_ > compact_above_ + 2 * stored_bytes_ &&
      !compact(error))
    return false;
  if (!file_) file_ = std::make_shared<SpillFile>("map blocks");
  encode(voxels, encoded_);
  Stored stored;
  if (!file_->append(encoded_, {}, stored.offset, error)) return false;
  stored.bytes = static_cast<std::uint32_t>(encoded_.size());
  stored.surface_points = surface_points;
  stored.touched_in = touched_in;
  stored.least_sdf = INT16_MAX;
  stored.greatest_sdf = INT16_MIN;
  for (const TsdfVoxel& v : voxels) {
    if (!v.observed()) continue;
    stored.least_sdf = std::min(stored.least_sdf, v.sdf_steps);
    stored.greatest_sdf = std::max(stored.greatest_sdf, v.sdf_steps);
  }
  erase(key);  // a block stored again replaces what was stored of it
  index_.emplace(key, stored);
  stored_bytes_ += stored.bytes;
  return true;
}

bool BlockStore::read(const Stored& stored, Voxels& voxels, std::vector<std::uint8_t>& scratch,
                      std::string& error) const {
  if (!file_) {
    error = "map blocks: no scratch file";
    return false;
  }
  if (!file_->read(stored.offset, stored.bytes, scratch, error)) return false;
  if (!decode(scratch, voxels)) {
    error = "map blocks: a block read back is not one that was written";
    return false;
  }
  return true;
}

void BlockStore::erase(std::uint64_t key) {
  const auto it = index_.find(key);
  if (it == index_.end()) return;
  stored_bytes_ -= it->second.bytes;
  index_.erase(it);
}

void BlockStore::clear() {
  index_.clear();
  file_.reset();
  stored_bytes_ = 0;
}

bool BlockStore::compact(std::string& error) {
  auto file = std::make_shared<SpillFile>("map blocks");
  Index index;
  index.reserve(index_.size());
  for (const auto& [key, stored] : index_) {
    if (!file_->read(stored.offset, stored.bytes, scratch_, error)) return false;
    Stored moved = stored;
    if (!file->append(scratch_, {}, moved.offset, error)) return false;
    index.emplace(key, moved);
  }
  index_ = std::move(index);
  file_ = std::move(file);
  return true;
}

}  // namespace rgbdmap
