#include "rgbdmap/map_files/ply_file.hpp"

#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <vector>

#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_io.hpp"
#include "rgbdmap/map_files/atomic_write.hpp"

namespace rgbdmap {
namespace {

constexpr std::size_t kVertexBytes = 15;  // 3 floats, 3 uchars
constexpr std::size_t kFaceBytes = 13;    // uchar 3, 3 ints

bool writePly(const TriangleMesh& mesh, int fd) {
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by rgbdmap\n"
         << "element vertex " << mesh.vertices.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
         << "element face " << mesh.triangles.size() << "\n"
         << "property list uchar int vertex_indices\nend_header\n";
  const std::string text = header.str();
  if (!writeAll(fd, text.data(), text.size())) return false;
  // In chunks: a large mesh is written without a second copy of it in memory.
  constexpr std::size_t kChunk = 16384;
  std::vector<char> buffer(kChunk * kVertexBytes);
  for (std::size_t first = 0; first < mesh.vertices.size(); first += kChunk) {
    const std::size_t count = std::min(kChunk, mesh.vertices.size() - first);
    char* out = buffer.data();
    for (std::size_t i = first; i < first + count; ++i, out += kVertexBytes) {
      std::memcpy(out, mesh.vertices[i].data(), 12);
      std::memcpy(out + 12, mesh.colours[i].data(), 3);
    }
    if (!writeAll(fd, buffer.data(), count * kVertexBytes)) return false;
  }
  for (std::size_t first = 0; first < mesh.triangles.size(); first += kChunk) {
    const std::size_t count = std::min(kChunk, mesh.triangles.size() - first);
    char* out = buffer.data();
    for (std::size_t i = first; i < first + count; ++i, out += kFaceBytes) {
      out[0] = 3;
      std::memcpy(out + 1, mesh.triangles[i].data(), 12);  // int: indices stay below 2^31
    }
    if (!writeAll(fd, buffer.data(), count * kFaceBytes)) return false;
  }
  return true;
}

// PLY's scalar types by name and size in bytes (0: unknown).
std::size_t typeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
      type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

double readScalar(const char* at, const std::string& type) {
  auto get = [at](auto value) {
    std::memcpy(&value, at, sizeof(value));
    return static_cast<double>(value);
  };
  if (type == "char" || type == "int8") return get(std::int8_t{});
  if (type == "uchar" || type == "uint8") return get(std::uint8_t{});
  if (type == "short" || type == "int16") return get(std::int16_t{});
  if (type == "ushort" || type == "uint16") return get(std::uint16_t{});
  if (type == "int" || type == "int32") return get(std::int32_t{});
  if (type == "uint" || type == "uint32") return get(std::uint32_t{});
  if (type == "float" || type == "float32") return get(float{});
  return get(double{});
}

struct Property {
  std::string name, type;
  std::string count_type;  // list properties only
  std::size_t offset = 0;  // within the element's record (scalar properties of fixed records)
};
struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
  bool fixed = true;  // no list property: every record has the same size
  std::size_t bytes = 0;
  const Property* find(const std::string& name) const {
    for (const Property& p : properties)
      if (p.name == name) return &p;
    return nullptr;
  }
};

// A PLY file being read: its bytes, where reading is, and errors naming the file.
struct PlyReader {
  std::string path;
  std::string data;
  std::size_t at = 0;

  InputError fail(const std::string& what) const { return InputError(path + ": " + what); }
  InputError truncated(const Element& e, std::size_t i) const {
    return fail("truncated: the file ends in " + e.name + " " + std::to_string(i) + " of " +
                std::to_string(e.count));
  }
  std::size_t left() const { return data.size() - at; }

  // One line of the header ("element", "property", ...) added to `elements`; false at end_header.
  bool headerLine(const std::string& line, std::size_t line_number, bool& binary,
                  std::vector<Element>& elements) const;
  // The header: text lines up to "end_header".
  std::vector<Element> header();
  void vertices(const Element& e, TriangleMesh& mesh);
  // Faces (or another element with lists), record by record.
  void lists(const Element& e, TriangleMesh& mesh);
};

bool PlyReader::headerLine(const std::string& line, std::size_t line_number, bool& binary,
                           std::vector<Element>& elements) const {
  std::istringstream words(line);
  std::string keyword;
  words >> keyword;
  if (line_number == 1) {
    if (keyword != "ply") throw fail("not a PLY file (it does not start with \"ply\")");
    return true;
  }
  const std::string where = "header line " + std::to_string(line_number) + ": ";
  if (keyword == "end_header") return false;
  if (keyword == "comment" || keyword == "obj_info" || keyword.empty()) return true;
  if (keyword == "format") {
    std::string format;
    words >> format;
    if (format != "binary_little_endian")
      throw fail(where + "format " + format +
                 " is not supported (binary_little_endian is: save as binary PLY)");
    binary = true;
  } else if (keyword == "element") {
    Element e;
    long long count = -1;
    words >> e.name >> count;
    if (!words || count < 0) throw fail(where + "bad element line \"" + line + "\"");
    e.count = static_cast<std::size_t>(count);
    elements.push_back(e);
  } else if (keyword == "property") {
    if (elements.empty()) throw fail(where + "a property before any element");
    Element& e = elements.back();
    Property p;
    words >> p.type;
    if (p.type == "list") {
      words >> p.count_type >> p.type;
      if (typeSize(p.count_type) == 0 || p.count_type == "float" || p.count_type == "double")
        throw fail(where + "bad list count type \"" + p.count_type + "\"");
      e.fixed = false;
    }
    words >> p.name;
    if (!words || typeSize(p.type) == 0) throw fail(where + "bad property \"" + line + "\"");
    p.offset = e.bytes;
    e.bytes += typeSize(p.type);
    e.properties.push_back(p);
  } else {
    throw fail(where + "unknown keyword \"" + keyword + "\"");
  }
  return true;
}

std::vector<Element> PlyReader::header() {
  std::vector<Element> elements;
  bool binary = false;
  for (std::size_t line_number = 1;; ++line_number) {
    const std::size_t end = data.find('\n', at);
    if (end == std::string::npos) throw fail("no end_header: not a complete PLY header");
    std::string line = data.substr(at, end - at);
    at = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!headerLine(line, line_number, binary, elements)) break;
  }
  if (!binary) throw fail("no format line in the header");
  return elements;
}

void PlyReader::vertices(const Element& e, TriangleMesh& mesh) {
  if (!e.fixed) throw fail("a list property in element vertex is not supported");
  const Property *x = e.find("x"), *y = e.find("y"), *z = e.find("z");
  if (!x || !y || !z) throw fail("element vertex has no x, y and z");
  const Property *r = e.find("red"), *g = e.find("green"), *b = e.find("blue");
  // Checked before allocating: a corrupt count must not ask for terabytes.
  if (e.bytes == 0 || left() / e.bytes < e.count)
    throw truncated(e, left() / std::max<std::size_t>(e.bytes, 1));
  mesh.vertices.resize(e.count);
  mesh.colours.assign(e.count, {200, 200, 200});
  for (std::size_t i = 0; i < e.count; ++i, at += e.bytes) {
    const char* record = data.data() + at;
    mesh.vertices[i] = Eigen::Vector3f(static_cast<float>(readScalar(record + x->offset, x->type)),
                                       static_cast<float>(readScalar(record + y->offset, y->type)),
                                       static_cast<float>(readScalar(record + z->offset, z->type)));
    if (r && g && b)
      mesh.colours[i] = {static_cast<std::uint8_t>(readScalar(record + r->offset, r->type)),
                         static_cast<std::uint8_t>(readScalar(record + g->offset, g->type)),
                         static_cast<std::uint8_t>(readScalar(record + b->offset, b->type))};
  }
}

void PlyReader::lists(const Element& e, TriangleMesh& mesh) {
  const bool faces = e.name == "face";
  for (std::size_t i = 0; i < e.count; ++i) {
    std::vector<std::uint32_t> polygon;
    for (const Property& p : e.properties) {
      const bool indices = faces && (p.name == "vertex_indices" || p.name == "vertex_index");
      std::size_t values = 1;
      if (!p.count_type.empty()) {
        if (left() < typeSize(p.count_type)) throw truncated(e, i);
        const double n = readScalar(data.data() + at, p.count_type);
        at += typeSize(p.count_type);
        if (n < 0) throw fail(e.name + " " + std::to_string(i) + ": a negative list length");
        values = static_cast<std::size_t>(n);
      }
      if (left() / typeSize(p.type) < values) throw truncated(e, i);
      for (std::size_t k = 0; k < values; ++k, at += typeSize(p.type)) {
        if (!indices) continue;
        const double index = readScalar(data.data() + at, p.type);
        if (index < 0 || index >= static_cast<double>(mesh.vertices.size()))
          throw fail("face " + std::to_string(i) + ": vertex index " +
                     std::to_string(static_cast<long long>(index)) + " is out of range (" +
                     std::to_string(mesh.vertices.size()) + " vertices)");
        polygon.push_back(static_cast<std::uint32_t>(index));
      }
    }
    if (!faces) continue;
    if (polygon.size() < 3)
      throw fail("face " + std::to_string(i) + " has " + std::to_string(polygon.size()) +
                 " vertices");
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
      mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
  }
}

}  // namespace

bool writePlyAtomically(const TriangleMesh& mesh, const std::string& path, std::string& error) {
  return writeFileAtomically(
      path, [&](int fd) { return writePly(mesh, fd); }, error);
}

TriangleMesh readPly(const std::string& path) {
  PlyReader ply{path, "", 0};
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ply.fail("cannot open the file");
  ply.data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  TriangleMesh mesh;
  for (const Element& e : ply.header()) {
    if (e.name == "vertex") {
      ply.vertices(e, mesh);
    } else if (e.fixed) {  // an element we do not use: skipped whole
      if (e.bytes != 0 && ply.left() / e.bytes < e.count) throw ply.truncated(e, 0);
      ply.at += e.bytes * e.count;
    } else {
      ply.lists(e, mesh);
    }
  }
  if (ply.at != ply.data.size())
    throw ply.fail(std::to_string(ply.left()) +
                   " bytes after the last element: not the size the header gives");
  return mesh;
}

}  // namespace rgbdmap
