#include "rgbdmap/map_files/atomic_write.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "rgbdmap/base/file_io.hpp"

namespace rgbdmap {
namespace {

std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

// "File too large (EFBIG)": the symbolic name for the errors a user can act on.
std::string describeErrno(int error) {
  std::string text = std::strerror(error);
  switch (error) {
    case EFBIG:
      return text + " (EFBIG: a file-size limit, ulimit -f)";
    case ENOSPC:
      return text + " (ENOSPC)";
    case EDQUOT:
      return text + " (EDQUOT)";
    case EROFS:
      return text + " (EROFS)";
    case EACCES:
      return text + " (EACCES)";
    default:
      return text;
  }
}

}  // namespace

// The pid keeps two runs that write the same map (by mistake) from writing one temporary file.
std::string temporaryFileOf(const std::string& path) {
  return path + ".tmp-" + std::to_string(::getpid());
}

bool writeFileAtomically(const std::string& path, const std::function<bool(int fd)>& write,
                         std::string& error) {
  const std::string tmp = temporaryFileOf(path);
  const auto fail = [&](const std::string& what, int fd) {
    const int saved = errno;
    error = path + ": " + what + " " + tmp + ": " + describeErrno(saved);
    if (fd >= 0) ::close(fd);
    std::remove(tmp.c_str());
    return false;
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return fail("cannot create", -1);
  if (!write(fd)) return fail("cannot write", fd);
  if (::fsync(fd) != 0) return fail("cannot fsync", fd);  // ENOSPC may only show here (NFS)
  if (::close(fd) != 0) return fail("cannot close", -1);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) return fail("cannot rename into place", -1);
  // Makes the rename itself durable; the map is complete either way.
  const int folder = ::open(folderOf(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (folder >= 0) {
    ::fsync(folder);
    ::close(folder);
  }
  return true;
}

bool writeBytesAtomically(const std::string& path, const std::string& bytes, std::string& error) {
  return writeFileAtomically(
      path, [&bytes](int fd) { return writeAll(fd, bytes.data(), bytes.size()); }, error);
}

}  // namespace rgbdmap
