#include "rgbdmap/base/binary_record.hpp"

#include <cerrno>
#include <fstream>
#include <sstream>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap {
namespace {

constexpr char kMagic[8] = {'R', 'G', 'B', 'D', 'M', 'A', 'P', '\0'};

struct Header {
  char magic[8];
  char kind[4];
  std::uint32_t version;
  std::uint64_t size;
  std::uint64_t hash;
};
static_assert(sizeof(Header) == 32, "the header is 32 bytes on disk");

std::uint64_t fnv1a(const char* data, std::size_t size) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

}  // namespace

void BinaryReader::getBytes(void* out, std::size_t size) {
  if (size > data_.size() - at_) fail("truncated or corrupt (a value runs past the end)");
  std::memcpy(out, data_.data() + at_, size);
  at_ += size;
}

std::string BinaryReader::getString() {
  const std::size_t size = count(1);
  std::string text(data_.data() + at_, size);
  at_ += size;
  return text;
}

std::size_t BinaryReader::count(std::size_t element_bytes) {
  const auto n = get<std::uint64_t>();
  if (element_bytes == 0) element_bytes = 1;
  if (n > (data_.size() - at_) / element_bytes)
    fail("truncated or corrupt (a count of " + std::to_string(n) + " exceeds what is left)");
  return static_cast<std::size_t>(n);
}

void BinaryReader::fail(const std::string& what) const { throw InputError(file_ + ": " + what); }

std::string sealRecord(const char (&kind)[5], std::uint32_t version, const std::string& payload) {
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  std::memcpy(header.kind, kind, 4);
  header.version = version;
  header.size = payload.size();
  header.hash = fnv1a(payload.data(), payload.size());
  std::string out(reinterpret_cast<const char*>(&header), sizeof header);
  out += payload;
  return out;
}

BinaryReader openRecord(const std::string& path, const char (&kind)[5], std::uint32_t version) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open (" + std::strerror(errno) + ")");
  std::ostringstream content;
  content << in.rdbuf();
  std::string data = std::move(content).str();
  Header header{};
  if (data.size() < sizeof header || std::memcmp(data.data(), kMagic, sizeof kMagic) != 0)
    throw InputError(path + ": not an rgbdmap file (no RGBDMAP header)");
  std::memcpy(&header, data.data(), sizeof header);
  if (std::memcmp(header.kind, kind, 4) != 0)
    throw InputError(path + ": holds '" + std::string(header.kind, 4) + "', expected '" + kind +
                     "'");
  if (header.version != version)
    throw InputError(path + ": format version " + std::to_string(header.version) +
                     ", this rgbdmap reads version " + std::to_string(version));
  if (data.size() - sizeof header != header.size)
    throw InputError(path + ": truncated (" + std::to_string(data.size() - sizeof header) + " of " +
                     std::to_string(header.size) + " bytes)");
  if (fnv1a(data.data() + sizeof header, header.size) != header.hash)
    throw InputError(path + ": corrupt (its checksum does not match)");
  data.erase(0, sizeof header);
  return BinaryReader(std::move(data), path);
}

}  // namespace rgbdmap
