#include "rgbdmap/base/binary_record.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <fstream>
#include <sstream>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_io.hpp"

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

constexpr std::uint64_t kFnvOffset = 0xcbf29ce484222325ull;
constexpr std::size_t kBufferBytes = 1 << 20;

std::uint64_t fnv1a(const char* data, std::size_t size, std::uint64_t hash = kFnvOffset) {
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

}  // namespace

void BinaryReader::getBytes(void* out, std::size_t size) {
  if (size == 0) return;  // `out` may be an empty vector's null data()
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

RecordWriter::RecordWriter(int fd, const char (&kind)[5], std::uint32_t version)
    : fd_(fd), version_(version), hash_(kFnvOffset) {
  std::memcpy(kind_, kind, 4);
  buffer_.assign(sizeof(Header), '\0');  // filled in by finish()
  buffer_.reserve(kBufferBytes);
}

RecordWriter::RecordWriter(std::string& sink, const char (&kind)[5], std::uint32_t version)
    : sink_(&sink), version_(version), hash_(kFnvOffset) {
  std::memcpy(kind_, kind, 4);
  sink.clear();
  buffer_.assign(sizeof(Header), '\0');  // filled in by finish()
}

void RecordWriter::putBytes(const void* data, std::size_t size) {
  if (size == 0) return;
  const char* bytes = static_cast<const char*>(data);
  hash_ = fnv1a(bytes, size, hash_);
  size_ += size;
  while (size > 0) {
    const std::size_t take = std::min(size, kBufferBytes - std::min(kBufferBytes, buffer_.size()));
    buffer_.append(bytes, take);
    bytes += take;
    size -= take;
    if (buffer_.size() >= kBufferBytes) flush();
  }
}

void RecordWriter::flush() {
  if (sink_) {
    sink_->append(buffer_);
    buffer_.clear();
    return;
  }
  if (ok_ && !writeAll(fd_, buffer_.data(), buffer_.size())) {
    ok_ = false;
    error_ = errno;
  }
  buffer_.clear();
}

bool RecordWriter::finish() {
  flush();
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  std::memcpy(header.kind, kind_, 4);
  header.version = version_;
  header.size = size_;
  header.hash = hash_;
  if (sink_) {
    std::memcpy(sink_->data(), &header, sizeof header);
    return true;
  }
  if (ok_ && ::pwrite(fd_, &header, sizeof header, 0) != static_cast<ssize_t>(sizeof header)) {
    ok_ = false;
    error_ = errno;
  }
  if (!ok_) errno = error_;
  return ok_;
}

BinaryReader openRecord(const std::string& path, const char (&kind)[5], std::uint32_t version) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open (" + std::strerror(errno) + ")");
  std::ostringstream content;
  content << in.rdbuf();
  return readRecord(std::move(content).str(), path, kind, version);
}

std::string recordKind(const std::string& data) {
  if (data.size() < sizeof(Header) || std::memcmp(data.data(), kMagic, sizeof kMagic) != 0)
    return "";
  return data.substr(sizeof kMagic, 4);
}

BinaryReader readRecord(std::string data, const std::string& path, const char (&kind)[5],
                        std::uint32_t version) {
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
