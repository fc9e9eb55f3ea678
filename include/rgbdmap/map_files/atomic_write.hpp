#pragma once

#include <functional>
#include <string>

namespace rgbdmap {

// Every map file (PCD, PLY, grid, OctoMap, a rewritten trajectory, a session's files) is written
// so that its destination only ever holds a complete file: write "<path>.tmp-<pid>", fsync it,
// rename it over the destination, fsync the folder.

// "<path>.tmp-<pid>": where writeFileAtomically writes `path` before renaming it into place (the
// name a second Ctrl-C removes, see output_files.hpp).
std::string temporaryFileOf(const std::string& path);

// `write` writes the whole file to `fd` (false with errno set). Returns false with `error` naming
// the path and the system error (EFBIG, ENOSPC, EDQUOT, EROFS, ...) when anything fails; the
// temporary file is removed and the destination left as it was.
bool writeFileAtomically(const std::string& path, const std::function<bool(int fd)>& write,
                         std::string& error);
// The same for bytes held in memory (a text, an encoded image).
bool writeBytesAtomically(const std::string& path, const std::string& bytes, std::string& error);

}  // namespace rgbdmap
