#include "rgbdmap/sessions/session_file.hpp"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

#include "rgbdmap/base/binary_record.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/base/file_io.hpp"
#include "rgbdmap/map_files/atomic_write.hpp"
#include "rgbdmap/sessions/session_records.hpp"

namespace rgbdmap {
namespace {

namespace fs = std::filesystem;

// The files of a session folder (docs/sessions.md describes each).
constexpr const char* kSummaryFile = "session.yaml";
constexpr const char* kConfigFile = "config.yaml";
constexpr const char* kGraphFile = "graph.bin";
constexpr const char* kPlacesFile = "places.bin";
constexpr const char* kKeyframesFile = "keyframes.bin";
constexpr const char* kImagesFile = "images.bin";
constexpr const char* kPlacesDataFile = "places.data";
constexpr const char* kStreamsFile = "streams.bin";
constexpr const char* kFramesFile = "frames.anchored";
constexpr const char* kFusedFile = "keyframes.anchored";
constexpr char kGraphKind[5] = "GRPH";
constexpr char kPlacesKind[5] = "PLCS";         // places inside (sessions before places.data)
constexpr char kPlaceIndexKind[5] = "PLIX";     // places in places.data
constexpr char kPlaceKind[5] = "PLCE";          // one place, in places.data
constexpr char kKeyframesKind[5] = "KFRM";      // images inside (sessions before images.bin)
constexpr char kKeyframeIndexKind[5] = "KFIX";  // images in images.bin
constexpr char kStreamsKind[5] = "STRM";

// The graph's keyframes and edges, counted into `summary`, from a saved graph or a live one.
template <typename Graph>
void putGraph(const Graph& graph, RecordWriter& out, SessionSummary& summary) {
  summary.keyframes = graph.keyframes();
  out.put<std::uint64_t>(summary.keyframes);
  for (std::size_t id = 0; id < summary.keyframes; ++id) {
    const LoopCloser::Saved::Keyframe k = graph.keyframe(id);
    out.put(k.timestamp);
    putPose(out, k.odometry);
    putPose(out, k.pose);
  }
  summary.edges = graph.edges().size();
  out.put<std::uint64_t>(summary.edges);
  for (const PoseGraph::Edge& e : graph.edges()) {
    putEdge(out, e);
    summary.loop_edges += e.loop ? 1 : 0;
  }
}

// A saved graph seen like a live one (LoopCloser::GraphView).
struct SavedGraphView {
  const LoopCloser::Saved& saved;
  std::size_t keyframes() const { return saved.keyframes.size(); }
  const LoopCloser::Saved::Keyframe& keyframe(std::size_t id) const { return saved.keyframes[id]; }
  const std::vector<PoseGraph::Edge>& edges() const { return saved.edges; }
};

void writeGraph(const Session& s, RecordWriter& out, SessionSummary& summary) {
  putCamera(out, s.camera);
  if (s.live_graph)
    s.live_graph->readGraph(
        [&](const LoopCloser::GraphView& graph) { putGraph(graph, out, summary); });
  else
    putGraph(SavedGraphView{s.graph}, out, summary);
}

void readGraph(BinaryReader in, Session& s) {
  s.camera = getCamera(in);
  const std::size_t keyframes = in.count(8 + 2 * 12 * 8);
  s.graph.keyframes.resize(keyframes);
  for (LoopCloser::Saved::Keyframe& k : s.graph.keyframes) {
    k.timestamp = in.get<double>();
    k.odometry = getPose(in);
    k.pose = getPose(in);
  }
  const std::size_t edges = in.count(9 + 48 * 8);
  s.graph.edges.resize(edges);
  for (PoseGraph::Edge& e : s.graph.edges) e = getEdge(in, keyframes);
  if (!in.atEnd()) in.fail("corrupt (bytes after the edges)");
}

// A place as a record of its own (kind PLCE) in places.data: its view and its dense reference,
// expanded as the aligner takes it (packing again gives the same points).
std::string placeRecord(const PlaceRecognition::Place& place, AlignmentReference& reference) {
  std::string bytes;
  RecordWriter out(bytes, kPlaceKind, Session::kFormatVersion);
  putView(out, place.view);
  place.reference.expand(reference);
  out.put<std::int32_t>(reference.valid_pixels);
  out.put<std::uint64_t>(reference.levels.size());
  for (const AlignmentReference::Level& level : reference.levels) {
    out.put(level.camera);
    out.put<std::uint64_t>(level.points.size());
    out.putBytes(level.points.data(), level.points.size() * sizeof(Eigen::Vector4f));
  }
  out.finish();
  return bytes;
}

// The place of one record (what placeRecord() wrote, or one place of an older places.bin).
std::shared_ptr<const PlaceRecognition::Place> getPlace(BinaryReader& in,
                                                        AlignmentReference& reference) {
  auto place = std::make_shared<PlaceRecognition::Place>();
  place->view = getView(in);
  reference.valid_pixels = in.get<std::int32_t>();
  reference.levels.resize(in.count(sizeof(LevelCamera)));
  for (AlignmentReference::Level& level : reference.levels) {
    level.camera = in.get<LevelCamera>();
    level.points.resize(in.count(sizeof(Eigen::Vector4f)));
    in.getBytes(level.points.data(), level.points.size() * sizeof(Eigen::Vector4f));
  }
  place->reference = PackedReference::pack(reference);
  return place;
}

// A file of a new session folder that a run's sessions only add to: linked to the same file of
// the session last written at `path` when `known` still describes it (and `may_link`), and then
// written from the end that session knows; else written from empty.
class AppendedFile {
 public:
  AppendedFile(const std::string& path, const char* name, const std::string& file,
               const SessionAppends* log, const SessionAppends::File* known, bool may_link)
      : file_(file) {
    const std::string last = path + "/" + name;
    struct stat st {};
    linked_ = log != nullptr && may_link && log->session == path &&
              ::stat(last.c_str(), &st) == 0 && st.st_ino == known->inode &&
              static_cast<std::uint64_t>(st.st_size) >= known->bytes &&
              ::link(last.c_str(), file.c_str()) == 0;
    fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | (linked_ ? 0 : O_TRUNC), 0644);
    end_ = linked_ ? known->bytes : 0;
    // What a failed write of an earlier session left past the end its index knows goes.
    ok_ = fd_ >= 0 && ::ftruncate(fd_, static_cast<off_t>(end_)) == 0 &&
          ::lseek(fd_, static_cast<off_t>(end_), SEEK_SET) >= 0;
  }
  ~AppendedFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  AppendedFile(const AppendedFile&) = delete;
  AppendedFile& operator=(const AppendedFile&) = delete;

  bool linked() const { return linked_; }
  std::uint64_t end() const { return end_; }
  bool append(const void* data, std::size_t size) {
    ok_ = ok_ && writeAll(fd_, static_cast<const char*>(data), size);
    end_ += size;
    return ok_;
  }
  // Synced: `now` describes it. False with `error` naming the file and the system error.
  bool finish(SessionAppends::File& now, std::string& error) {
    struct stat st {};
    ok_ = ok_ && ::fdatasync(fd_) == 0 && ::fstat(fd_, &st) == 0;
    if (!ok_) {
      error = file_ + ": cannot write: " + std::strerror(errno);
      return false;
    }
    now = {static_cast<std::uint64_t>(st.st_ino), end_};
    return true;
  }

 private:
  std::string file_;
  bool linked_ = false;
  int fd_ = -1;
  std::uint64_t end_ = 0;
  bool ok_ = false;
};

// After writeGraph(): at most one place a keyframe (a live loop closer may have added keyframes
// and places since) into places.data, after those of the last session written when `log` knows
// them. `at` gets where each graph keyframe's place is (bytes 0: none).
bool writePlaceData(const Session& s, std::size_t keyframes, const std::string& path,
                    const std::string& file, const SessionAppends* log,
                    std::vector<SessionAppends::PlaceAt>& at, SessionAppends& next,
                    std::string& error) {
  std::vector<std::shared_ptr<const PlaceRecognition::Place>> live;
  if (s.live_graph) live = s.live_graph->places();
  const auto& places = s.live_graph ? live : s.graph.places;
  const std::size_t count = std::min(places.size(), keyframes);
  AppendedFile out(path, kPlacesDataFile, file, log, log ? &log->places : nullptr, true);
  AlignmentReference reference;  // its buffers serve every place
  at.assign(count, {});
  for (std::size_t id = 0; id < count; ++id) {
    const PlaceRecognition::Place* place = places[id].get();
    if (place == nullptr) continue;
    const auto known = out.linked() ? log->places_by_id.find(id) : next.places_by_id.end();
    if (out.linked() && known != log->places_by_id.end() && known->second.second == place) {
      at[id] = known->second.first;
    } else {
      const std::string bytes = placeRecord(*place, reference);
      at[id] = {out.end(), bytes.size()};
      if (!out.append(bytes.data(), bytes.size())) break;
      next.appended += bytes.size();
    }
    next.places_by_id[id] = {at[id], place};
  }
  return out.finish(next.places, error);
}

void writePlaceIndex(const std::vector<SessionAppends::PlaceAt>& at, RecordWriter& out,
                     SessionSummary& summary) {
  out.put<std::uint64_t>(at.size());
  for (const SessionAppends::PlaceAt& place : at) {
    out.put<std::uint8_t>(place.bytes > 0 ? 1 : 0);
    if (place.bytes == 0) continue;
    ++summary.places;
    out.put(place);
  }
}

// A session's places: places.bin an index into places.data, or (before places.data) the places
// themselves.
void readPlaces(BinaryReader in, Session& s, const std::string& data_path) {
  const bool indexed = !data_path.empty();
  std::ifstream data;
  std::uint64_t data_bytes = 0;
  if (indexed) {
    data.open(data_path, std::ios::binary);
    if (!data) throw InputError(data_path + ": cannot open (" + std::strerror(errno) + ")");
    std::error_code ec;
    data_bytes = fs::file_size(data_path, ec);
  }
  // At most one a keyframe: a place is added to the loop closer after its graph's node, so a
  // session written while it runs may have fewer (the newest keyframes then have none).
  const std::size_t count = in.count(1);
  if (count > s.graph.keyframes.size())
    in.fail("corrupt (" + std::to_string(count) + " places for " +
            std::to_string(s.graph.keyframes.size()) + " keyframes)");
  s.graph.places.resize(count);
  AlignmentReference reference;  // as read, before packing (its buffers serve every place)
  std::string bytes;
  for (auto& slot : s.graph.places) {
    if (in.get<std::uint8_t>() == 0) continue;
    if (!indexed) {
      slot = getPlace(in, reference);
      continue;
    }
    const auto at = in.get<SessionAppends::PlaceAt>();
    bytes.resize(at.bytes);
    if (at.offset > data_bytes || at.bytes > data_bytes - at.offset ||
        !data.seekg(static_cast<std::streamoff>(at.offset)) ||
        !data.read(bytes.data(), static_cast<std::streamsize>(bytes.size())))
      throw InputError(data_path + ": truncated (" + std::to_string(data_bytes) +
                       " bytes; places.bin names a place at byte " + std::to_string(at.offset) +
                       ")");
    BinaryReader place =
        readRecord(bytes, data_path + " (the place at byte " + std::to_string(at.offset) + ")",
                   kPlaceKind, Session::kFormatVersion);
    slot = getPlace(place, reference);
    if (!place.atEnd()) place.fail("corrupt (bytes after the place)");
  }
  if (!in.atEnd()) in.fail("corrupt (bytes after the places)");
  s.graph.places.resize(s.graph.keyframes.size());
}

std::shared_ptr<const std::vector<std::uint8_t>> getBlob(BinaryReader& in) {
  std::vector<std::uint8_t> blob(in.count(1));
  in.getBytes(blob.data(), blob.size());
  return std::make_shared<const std::vector<std::uint8_t>>(std::move(blob));
}

// A kept keyframe's images: in memory, or the bytes its scratch file holds.
std::uint64_t imageBytesOf(const KeyframeStore::Entry& e) {
  return e.on_disk ? e.depth_bytes + e.colour_bytes : e.imageBytes();
}

// The kept keyframes' images into `file` (images.bin): after those of the last session written
// at `path` when `log` knows them (the file linked, not copied), else all of them. `at` gets
// where each kept keyframe's are; `next` what the log becomes once the session is in place.
bool writeImages(const Session& s, const std::string& path, const std::string& file,
                 const SessionAppends* log, std::vector<SessionAppends::ImagesAt>& at,
                 SessionAppends& next, std::string& error) {
  std::uint64_t kept = 0;
  // Known by their store's ids: keyframes that share one (read, not a run's) are written whole.
  std::unordered_set<std::uint64_t> ids;
  bool unique = true;
  for (const KeyframeStore::Entry& e : s.keyframes) {
    kept += imageBytesOf(e);
    unique = ids.insert(e.id).second && unique;
  }
  // Written anew once the images let go outweigh those kept (and 64 MB).
  const bool may_link = unique && log != nullptr && log->images.bytes <= 2 * kept + (64u << 20);
  AppendedFile out(path, kImagesFile, file, log, log ? &log->images : nullptr, may_link);
  at.clear();
  try {
    for (const KeyframeStore::Entry& e : s.keyframes) {
      const auto known = out.linked() ? log->images_by_id.find(e.id) : next.images_by_id.end();
      if (out.linked() && known != log->images_by_id.end()) {
        at.push_back(known->second);
      } else {
        const auto depth = e.depthImage();  // read back from disk for the time of writing it
        const auto colour = e.colourImage();
        at.push_back({out.end(), depth->size(), colour->size()});
        if (!out.append(depth->data(), depth->size()) ||
            !out.append(colour->data(), colour->size()))
          break;
        next.appended += depth->size() + colour->size();
      }
      next.images_by_id[e.id] = at.back();
    }
  } catch (const std::runtime_error& e) {
    error = file + ": " + e.what();
    return false;
  }
  return out.finish(next.images, error);
}

void writeKeyframeIndex(const Session& s, const std::vector<SessionAppends::ImagesAt>& at,
                        RecordWriter& out, SessionSummary& summary) {
  out.put<double>(KeyframeStore::kInverseDepthUnits);
  out.put<std::int32_t>(KeyframeStore::kColourBitsDropped);
  summary.kept_keyframes = s.keyframes.size();
  out.put<std::uint64_t>(s.keyframes.size());
  for (std::size_t i = 0; i < s.keyframes.size(); ++i) {
    const KeyframeStore::Entry& e = s.keyframes[i];
    out.put(e.timestamp);
    out.put<std::uint64_t>(e.index);
    out.put<std::int64_t>(e.anchor);
    putPose(out, e.pose);
    putPose(out, e.fused_at);
    out.put(at[i]);
  }
}

// The image encoding every keyframes.bin starts with: refused unless it is this rgbdmap's.
void checkImageEncoding(BinaryReader& in) {
  if (in.get<double>() != KeyframeStore::kInverseDepthUnits ||
      in.get<std::int32_t>() != KeyframeStore::kColourBitsDropped)
    in.fail("images stored with another depth or colour encoding than this rgbdmap's");
}

// What keyframes.bin holds of a kept keyframe before its images (or where they are).
constexpr std::size_t kKeyframeHeadBytes = 8 + 8 + 8 + 2 * 12 * 8;
void getKeyframeHead(BinaryReader& in, KeyframeStore::Entry& e) {
  e.timestamp = in.get<double>();
  e.index = in.get<std::uint64_t>();
  e.anchor = in.get<std::int64_t>();
  e.pose = getPose(in);
  e.fused_at = getPose(in);
  // An anchor may lie beyond the graph: a checkpoint taken while the loop closer still had the
  // newest keyframes queued. Such a keyframe shares the newest correction, as in the run.
  if (e.anchor < -1)
    in.fail("corrupt (a kept keyframe anchored to " + std::to_string(e.anchor) + ")");
}

void readKeyframeIndex(BinaryReader in, Session& s, const std::string& images_path) {
  checkImageEncoding(in);
  std::ifstream images(images_path, std::ios::binary);
  if (!images) throw InputError(images_path + ": cannot open (" + std::strerror(errno) + ")");
  std::error_code ec;
  const std::uint64_t images_bytes = fs::file_size(images_path, ec);
  const auto blob = [&](std::uint64_t offset, std::uint64_t size) {
    std::vector<std::uint8_t> bytes(size);
    if (offset > images_bytes || size > images_bytes - offset || !images.seekg(offset) ||
        !images.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size)))
      throw InputError(images_path + ": truncated (" + std::to_string(images_bytes) +
                       " bytes; keyframes.bin names an image at byte " + std::to_string(offset) +
                       ")");
    return std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes));
  };
  s.keyframes.resize(in.count(kKeyframeHeadBytes + sizeof(SessionAppends::ImagesAt)));
  for (KeyframeStore::Entry& e : s.keyframes) {
    getKeyframeHead(in, e);
    const auto at = in.get<SessionAppends::ImagesAt>();
    e.depth_png = blob(at.offset, at.depth_bytes);
    e.colour_png = blob(at.offset + at.depth_bytes, at.colour_bytes);
  }
  if (!in.atEnd()) in.fail("corrupt (bytes after the keyframes)");
}

// A session written before images.bin: each kept keyframe's images inside keyframes.bin.
void readKeyframes(BinaryReader in, Session& s) {
  checkImageEncoding(in);
  s.keyframes.resize(in.count(kKeyframeHeadBytes + 16));
  for (KeyframeStore::Entry& e : s.keyframes) {
    getKeyframeHead(in, e);
    e.depth_png = getBlob(in);
    e.colour_png = getBlob(in);
  }
  if (!in.atEnd()) in.fail("corrupt (bytes after the keyframes)");
}

void writeStreams(const Session& s, RecordWriter& out, SessionSummary& /*summary*/) {
  out.put<std::uint64_t>(s.streams.size());
  for (const Session::Stream& stream : s.streams) {
    out.putString(stream.robot);
    out.put<std::uint64_t>(stream.records.size());
    for (const std::string& record : stream.records) out.putString(record);
  }
}

void readStreams(BinaryReader in, Session& s) {
  s.streams.resize(in.count(16));
  for (Session::Stream& stream : s.streams) {
    stream.robot = in.getString();
    stream.records.resize(in.count(8));
    for (std::string& record : stream.records) record = in.getString();
  }
  if (!in.atEnd()) in.fail("corrupt (bytes after the streams)");
}

// A trajectory of the session: copied from the run's spool while it runs (none yet: empty),
// else written from `poses`.
bool writeTrajectory(const std::string& path, const std::vector<AnchoredPose>& poses,
                     const std::string& spool, std::string& error) {
  return writeFileAtomically(
      path,
      [&](int fd) {
        if (!spool.empty()) {
          std::ifstream in(spool, std::ios::binary);
          if (!in && fs::exists(spool)) return false;
          std::vector<char> piece(1 << 16);
          while (in) {
            in.read(piece.data(), static_cast<std::streamsize>(piece.size()));
            if (!writeAll(fd, piece.data(), static_cast<std::size_t>(in.gcount()))) return false;
          }
          return true;
        }
        std::string text;
        for (const AnchoredPose& p : poses) {
          text += spoolLine(p);
          text.push_back('\n');
          if (text.size() > (1u << 16)) {
            if (!writeAll(fd, text.data(), text.size())) return false;
            text.clear();
          }
        }
        return writeAll(fd, text.data(), text.size());
      },
      error);
}

// Reads a trajectory of the session (none in a session written before they were kept).
std::vector<AnchoredPose> readTrajectory(const std::string& path) {
  std::vector<AnchoredPose> poses;
  std::error_code ec;
  if (!fs::exists(path, ec)) return poses;
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open (" + std::strerror(errno) + ")");
  std::size_t number = 0;
  AnchoredPose p;
  for (std::string line; std::getline(in, line);) {
    ++number;
    if (!parseSpoolLine(line, p) || p.anchor < -1)
      throw InputError(path + ": line " + std::to_string(number) +
                       ": corrupt (not \"timestamp tx ty tz qx qy qz qw anchor\")");
    poses.push_back(p);
  }
  return poses;
}

std::string summaryText(const Session& s, const SessionSummary& summary) {
  std::ostringstream out;
  out << "# rgbdmap session (docs/sessions.md): what a later run needs to go on from this map\n"
      << "format: rgbdmap-session\n"
      << "version: " << Session::kFormatVersion << "\n"
      << "created_by: " << s.created_by << "\n"
      << "keyframes: " << summary.keyframes << "\n"
      << "edges: " << summary.edges << "  # " << summary.loop_edges << " of them loops\n"
      << "places: " << summary.places << "\n"
      << "kept_keyframes: " << summary.kept_keyframes << "\n"
      << "camera: {width: " << s.camera.width << ", height: " << s.camera.height
      << ", fx: " << s.camera.fx << ", fy: " << s.camera.fy << ", cx: " << s.camera.cx
      << ", cy: " << s.camera.cy << "}\n";
  return out.str();
}

std::uint64_t folderBytes(const std::string& path) {
  std::uint64_t bytes = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(path, ec))
    if (entry.is_regular_file(ec)) bytes += entry.file_size(ec);
  return bytes;
}

void syncFolder(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// "version: N" of session.yaml, checked before anything else is read; returns its created_by.
std::string checkVersion(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open (" + std::strerror(errno) + ")");
  bool is_session = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("format: rgbdmap-session", 0) == 0) is_session = true;
    if (line.rfind("version: ", 0) != 0) continue;
    const std::string version = line.substr(9);
    if (!is_session) break;
    if (version != std::to_string(Session::kFormatVersion))
      throw InputError(path + ": session format version " + version +
                       ", this rgbdmap reads version " + std::to_string(Session::kFormatVersion));
    const std::string key = "created_by: ";
    while (std::getline(in, line))
      if (line.rfind(key, 0) == 0) return line.substr(key.size());
    return "";
  }
  throw InputError(path + ": not an rgbdmap session (no 'format: rgbdmap-session' and version)");
}

}  // namespace

SessionSummary summarise(const Session& s, const std::string& path) {
  SessionSummary summary;
  summary.keyframes = s.graph.keyframes.size();
  summary.edges = s.graph.edges.size();
  for (const PoseGraph::Edge& e : s.graph.edges) summary.loop_edges += e.loop ? 1 : 0;
  for (const auto& place : s.graph.places) summary.places += place ? 1 : 0;
  summary.kept_keyframes = s.keyframes.size();
  summary.bytes = folderBytes(path);
  return summary;
}

bool writeSession(const Session& session, const std::string& path, std::string& error,
                  std::uint64_t* bytes, SessionAppends* appends) {
  const std::string fresh = temporaryFileOf(path);
  std::error_code ec;
  fs::remove_all(fresh, ec);
  fs::create_directories(fresh, ec);
  if (ec) {
    error = path + ": cannot create " + fresh + ": " + ec.message();
    return false;
  }
  const auto in = [&fresh](const char* name) { return fresh + "/" + name; };
  SessionSummary summary;  // counted as written
  // Each record streamed to its file (the kept keyframes' images are tens of MB: never copied).
  const auto record =
      [&](const char* name, const char(&kind)[5],
          const std::function<void(const Session&, RecordWriter&, SessionSummary&)>& write) {
        // A kept keyframe's images read back from disk may fail (the scratch file's disk gone).
        std::string unreadable;
        const bool written = writeFileAtomically(
            in(name),
            [&](int fd) {
              try {
                RecordWriter out(fd, kind, Session::kFormatVersion);
                write(session, out, summary);
                return out.finish();
              } catch (const std::runtime_error& e) {
                unreadable = e.what();
                return false;
              }
            },
            error);
        if (!unreadable.empty()) error = in(name) + ": " + unreadable;
        return written;
      };
  // The places and images after those the last session of the run holds (appends).
  SessionAppends next;
  std::vector<SessionAppends::PlaceAt> places;
  std::vector<SessionAppends::ImagesAt> images;
  const auto placeIndex = [&places](const Session&, RecordWriter& out, SessionSummary& summary) {
    writePlaceIndex(places, out, summary);
  };
  const auto keyframeIndex = [&images](const Session& s, RecordWriter& out,
                                       SessionSummary& summary) {
    writeKeyframeIndex(s, images, out, summary);
  };
  const bool written =
      record(kGraphFile, kGraphKind, writeGraph) &&
      writePlaceData(session, summary.keyframes, path, in(kPlacesDataFile), appends, places, next,
                     error) &&
      record(kPlacesFile, kPlaceIndexKind, placeIndex) &&
      writeImages(session, path, in(kImagesFile), appends, images, next, error) &&
      record(kKeyframesFile, kKeyframeIndexKind, keyframeIndex) &&
      (session.streams.empty() || record(kStreamsFile, kStreamsKind, writeStreams)) &&
      writeTrajectory(in(kFramesFile), session.frames, session.frames_spool, error) &&
      writeTrajectory(in(kFusedFile), session.fused, session.fused_spool, error) &&
      writeBytesAtomically(in(kConfigFile), session.configuration, error) &&
      writeBytesAtomically(in(kSummaryFile), summaryText(session, summary), error);
  if (!written) {
    fs::remove_all(fresh, ec);
    return false;
  }
  syncFolder(fresh);
  // The new folder takes the old one's place in one step (the old one, now at `fresh`, goes).
  const bool exists = fs::exists(path, ec);
  const int swapped =
      exists ? ::renameat2(AT_FDCWD, fresh.c_str(), AT_FDCWD, path.c_str(), RENAME_EXCHANGE)
             : std::rename(fresh.c_str(), path.c_str());
  if (swapped != 0) {
    error = path + ": cannot move " + fresh + " into place: " + std::strerror(errno);
    fs::remove_all(fresh, ec);
    return false;
  }
  if (exists) fs::remove_all(fresh, ec);
  syncFolder(fs::absolute(path).parent_path().string());
  if (bytes) *bytes = folderBytes(path);
  if (appends) {
    next.session = path;
    *appends = std::move(next);
  }
  return true;
}

Session readSession(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec))
    throw InputError(path +
                     ": no session folder there (sessions are written beside the map as "
                     "MAP.session)");
  const auto in = [&path](const char* name) { return path + "/" + name; };
  Session session;
  session.created_by = checkVersion(in(kSummaryFile));
  {
    std::ifstream config(in(kConfigFile));
    if (!config) throw InputError(in(kConfigFile) + ": cannot open (" + std::strerror(errno) + ")");
    std::ostringstream text;
    text << config.rdbuf();
    session.configuration = text.str();
  }
  readGraph(openRecord(in(kGraphFile), kGraphKind, Session::kFormatVersion), session);
  // Since places.data, places.bin is an index into it; before, it held the places.
  if (fs::exists(in(kPlacesDataFile), ec))
    readPlaces(openRecord(in(kPlacesFile), kPlaceIndexKind, Session::kFormatVersion), session,
               in(kPlacesDataFile));
  else
    readPlaces(openRecord(in(kPlacesFile), kPlacesKind, Session::kFormatVersion), session, "");
  // Since images.bin, keyframes.bin is an index into it; before, it held the images.
  if (fs::exists(in(kImagesFile), ec))
    readKeyframeIndex(openRecord(in(kKeyframesFile), kKeyframeIndexKind, Session::kFormatVersion),
                      session, in(kImagesFile));
  else
    readKeyframes(openRecord(in(kKeyframesFile), kKeyframesKind, Session::kFormatVersion), session);
  if (fs::exists(in(kStreamsFile), ec))
    readStreams(openRecord(in(kStreamsFile), kStreamsKind, Session::kFormatVersion), session);
  session.frames = readTrajectory(in(kFramesFile));
  session.fused = readTrajectory(in(kFusedFile));
  return session;
}

PoseCorrections::Table correctionsOf(const Session& session) {
  PoseCorrections::Table table;
  table.reserve(session.graph.keyframes.size());
  for (const LoopCloser::Saved::Keyframe& k : session.graph.keyframes)
    table.push_back(k.pose * k.odometry.inverse());
  return table;
}

AnchoredPose anchoredInGraph(const Session& session, AnchoredPose pose) {
  const auto& graph = session.graph.keyframes;
  if (graph.empty()) return pose;
  if (pose.anchor < 0) {
    pose.pose = graph.front().odometry * graph.front().pose.inverse() * pose.pose;
    pose.anchor = 0;
  }
  pose.anchor = std::min<std::int64_t>(pose.anchor, static_cast<std::int64_t>(graph.size()) - 1);
  return pose;
}

namespace {
Trajectory inTimeOrder(std::vector<StampedPose> poses) {
  std::stable_sort(poses.begin(), poses.end(), [](const StampedPose& a, const StampedPose& b) {
    return a.timestamp < b.timestamp;
  });
  return Trajectory(std::move(poses));
}
}  // namespace

Trajectory graphTrajectory(const Session& session) {
  std::vector<StampedPose> poses;
  for (const auto& k : session.graph.keyframes) poses.push_back({k.timestamp, k.pose});
  return inTimeOrder(std::move(poses));
}

Trajectory resolvedTrajectory(const Session& session, const std::vector<AnchoredPose>& poses) {
  std::vector<StampedPose> resolved;
  if (session.graph.keyframes.empty()) return Trajectory(resolved);
  const PoseCorrections::Table corrections = correctionsOf(session);
  for (const AnchoredPose& p : poses) {
    const AnchoredPose a = anchoredInGraph(session, p);
    resolved.push_back({a.timestamp, corrections[static_cast<std::size_t>(a.anchor)] * a.pose});
  }
  return inTimeOrder(std::move(resolved));
}

void fuseSession(const Session& session, PoseCorrections& corrections, Mapper& mapper) {
  corrections.publish(correctionsOf(session));
  KeyframeStore decoder(0);
  Frame frame;
  for (const KeyframeStore::Entry& entry : session.keyframes) {
    decoder.decode(entry, frame);
    mapper.fuse(frame);
  }
  mapper.settle();
}

}  // namespace rgbdmap
