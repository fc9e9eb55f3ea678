#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

namespace rgbdmap {

// Binary files that say what they are and whether they are whole: a header (magic "RGBDMAP\0", a
// four-letter kind, a format version, the payload's size and its FNV-1a 64-bit hash) and the
// payload, little-endian as x86-64 and ARM64 store it. A reader refuses another kind, another
// version, a truncated file and a changed byte, with a message naming the file.

// Writes one record to a file as it goes (a payload of tens of MB is never held twice): a header
// left blank, the payload through a 1 MB buffer, hashed on the way, then the header filled in.
class RecordWriter {
 public:
  // `fd`: an empty file open for writing (and seeking).
  RecordWriter(int fd, const char (&kind)[5], std::uint32_t version);
  // Into memory: `sink` (emptied first) holds the whole record after finish(); a record sent as
  // a message is the same bytes as a file of it.
  RecordWriter(std::string& sink, const char (&kind)[5], std::uint32_t version);

  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values only");
    putBytes(&value, sizeof value);
  }
  void putBytes(const void* data, std::size_t size);
  void putString(const std::string& text) {
    put<std::uint64_t>(text.size());
    putBytes(text.data(), text.size());
  }
  // Writes what is buffered and the header. False (errno set) when any write failed.
  bool finish();

 private:
  void flush();

  int fd_ = -1;
  std::string* sink_ = nullptr;
  char kind_[4];
  std::uint32_t version_;
  std::string buffer_;
  std::uint64_t size_ = 0;
  std::uint64_t hash_;
  bool ok_ = true;
  int error_ = 0;
};

// Reads a payload back; every read past its end or count beyond what is left throws InputError
// naming the file ("truncated or corrupt").
class BinaryReader {
 public:
  BinaryReader(std::string data, std::string file)
      : data_(std::move(data)), file_(std::move(file)) {}

  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>, "plain values only");
    T value;
    getBytes(&value, sizeof value);
    return value;
  }
  void getBytes(void* out, std::size_t size);
  std::string getString();
  // A count of elements of at least `element_bytes` each that must fit in what is left.
  std::size_t count(std::size_t element_bytes);
  bool atEnd() const { return at_ == data_.size(); }
  [[noreturn]] void fail(const std::string& what) const;
  const std::string& file() const { return file_; }

 private:
  std::string data_;
  std::string file_;
  std::size_t at_ = 0;
};

// Reads `path` and checks its header against `kind` and `version`; throws InputError naming the
// file and what is wrong (missing, another kind, another version, truncated, corrupt).
BinaryReader openRecord(const std::string& path, const char (&kind)[5], std::uint32_t version);
// The same checks on a record held in memory (a message); `name` names it in the messages.
BinaryReader readRecord(std::string data, const std::string& name, const char (&kind)[5],
                        std::uint32_t version);
// A record's kind (its four letters), or "" when `data` does not start with a record header.
std::string recordKind(const std::string& data);

}  // namespace rgbdmap
