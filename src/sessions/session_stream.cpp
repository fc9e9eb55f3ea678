#include "rgbdmap/sessions/session_stream.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rgbdmap/base/binary_record.hpp"
#include "rgbdmap/base/error.hpp"
#include "rgbdmap/sessions/map_piece.hpp"
#include "rgbdmap/sessions/session_records.hpp"

namespace rgbdmap {
namespace {

constexpr char kStreamGraphKind[5] = "SGRF";
constexpr char kStreamPlaceKind[5] = "SPLC";
constexpr char kPieceKind[5] = "SPCE";
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kPoseBytes = 12 * 8;
constexpr std::size_t kEdgeBytes = 9 + kPoseBytes + 36 * 8;

void putPlace(RecordWriter& out, const PlaceRecognition::Place& place) {
  putView(out, place.view);
  const PackedReference& reference = place.reference;
  out.put<std::int32_t>(reference.valid_pixels);
  out.put<std::uint64_t>(reference.levels.size());
  for (const PackedReference::Level& level : reference.levels) {
    out.put(level.camera);
    out.put<std::uint64_t>(level.points.size());
    out.putBytes(level.points.data(), level.points.size() * sizeof(PackedReference::Point));
  }
}

std::shared_ptr<const PlaceRecognition::Place> getPlace(BinaryReader& in) {
  auto place = std::make_shared<PlaceRecognition::Place>();
  place->view = getView(in);
  PackedReference& reference = place->reference;
  reference.valid_pixels = in.get<std::int32_t>();
  reference.levels.resize(in.count(sizeof(LevelCamera)));
  for (PackedReference::Level& level : reference.levels) {
    level.camera = in.get<LevelCamera>();
    const LevelCamera& c = level.camera;
    if (c.width < 0 || c.height < 0 || !std::isfinite(c.fx) || !std::isfinite(c.fy) ||
        !std::isfinite(c.cx) || !std::isfinite(c.cy))
      in.fail("corrupt (a place's reference level with camera " + std::to_string(c.width) + "x" +
              std::to_string(c.height) + ")");
    level.points.resize(in.count(sizeof(PackedReference::Point)));
    in.getBytes(level.points.data(), level.points.size() * sizeof(PackedReference::Point));
  }
  return place;
}

void putImage(RecordWriter& out, const std::vector<std::uint8_t>& png) {
  out.put<std::uint64_t>(png.size());
  out.putBytes(png.data(), png.size());
}

std::shared_ptr<const std::vector<std::uint8_t>> getImage(BinaryReader& in) {
  std::vector<std::uint8_t> png(in.count(1));
  in.getBytes(png.data(), png.size());
  return std::make_shared<const std::vector<std::uint8_t>>(std::move(png));
}

// A graph record: the keyframes from `first` on and the edges from `first_edge` on.
template <typename Graph>
std::string graphRecord(std::uint64_t run, const CameraIntrinsics& camera, const Graph& graph,
                        std::size_t first, std::size_t first_edge) {
  std::string bytes;
  RecordWriter out(bytes, kStreamGraphKind, kVersion);
  out.put<std::uint64_t>(run);
  putCamera(out, camera);
  const std::size_t keyframes = graph.keyframes(), edges = graph.edges().size();
  out.put<std::uint64_t>(first);
  out.put<std::uint64_t>(keyframes - first);
  for (std::size_t id = first; id < keyframes; ++id) {
    const LoopCloser::Saved::Keyframe k = graph.keyframe(id);
    out.put(k.timestamp);
    putPose(out, k.odometry);
    putPose(out, k.pose);
  }
  out.put<std::uint64_t>(first_edge);
  out.put<std::uint64_t>(edges - first_edge);
  for (std::size_t i = first_edge; i < edges; ++i) putEdge(out, graph.edges()[i]);
  out.finish();
  return bytes;
}

std::string placeRecord(std::uint64_t run, std::size_t id, const PlaceRecognition::Place& place) {
  std::string bytes;
  RecordWriter out(bytes, kStreamPlaceKind, kVersion);
  out.put<std::uint64_t>(run);
  out.put<std::uint64_t>(id);
  putPlace(out, place);
  out.finish();
  return bytes;
}

std::string pieceRecord(std::uint64_t run, const KeyframeStore::Entry& e) {
  std::string bytes;
  RecordWriter out(bytes, kPieceKind, kVersion);
  out.put<std::uint64_t>(run);
  out.put<std::uint64_t>(e.index);
  out.put(e.timestamp);
  out.put<std::int64_t>(e.anchor);
  putPose(out, e.pose);
  putImage(out, *e.depthImage());
  putImage(out, *e.colourImage());
  out.finish();
  return bytes;
}

// An assembled graph seen like a live one (LoopCloser::GraphView).
struct AssembledGraph {
  const LoopCloser::Saved& saved;
  std::size_t keyframes() const { return saved.keyframes.size(); }
  const LoopCloser::Saved::Keyframe& keyframe(std::size_t id) const { return saved.keyframes[id]; }
  const std::vector<PoseGraph::Edge>& edges() const { return saved.edges; }
};

}  // namespace

SessionStream::SessionStream(std::uint64_t run, const CameraIntrinsics& camera, Options options)
    : run_(run),
      camera_(camera),
      options_(options),
      pieces_(static_cast<std::size_t>(std::max(0.0, options.piece_memory))) {}

void SessionStream::restart() {
  keyframes_sent_ = edges_sent_ = next_place_ = 0;
  next_piece_ = 0;
  ++totals_.restarts;
}

void SessionStream::addKeyframe(const Frame& keyframe) {
  if (last_piece_ && viewpointDistance(*last_piece_, keyframe.pose) < options_.piece_spacing)
    return;
  last_piece_ = keyframe.pose;
  makeMapPiece(keyframe, piece_);
  pieces_.add(pieces_.encode(piece_, piece_.pose));
}

std::vector<SessionStream::Record> SessionStream::take(const LoopCloser& graph, double now) {
  std::vector<Record> records;
  const double burst = options_.bytes_per_second * options_.burst_seconds;
  // The first call may spend a burst at once (the stream starts with its budget saved).
  budget_ = budget_at_ < 0.0
                ? burst
                : std::min(burst, budget_ + (now - budget_at_) * options_.bytes_per_second);
  budget_at_ = now;

  std::size_t keyframes = 0;
  std::string bytes;
  graph.readGraph([&](const LoopCloser::GraphView& view) {
    keyframes = view.keyframes();
    const std::size_t edges = view.edges().size();
    if (keyframes == keyframes_sent_ && edges == edges_sent_) return;
    bytes = graphRecord(run_, camera_, view, keyframes_sent_, edges_sent_);
    totals_.keyframes += keyframes - keyframes_sent_;
    totals_.edges += edges - edges_sent_;
    keyframes_sent_ = keyframes;
    edges_sent_ = edges;
  });
  if (!bytes.empty()) {
    budget_ -= static_cast<double>(bytes.size());
    totals_.bytes += bytes.size();
    records.push_back({Record::Kind::kGraph, std::move(bytes)});
  }

  // The newest keyframe's place may still be let go (when an older one is near); the ones
  // before it are settled.
  const std::size_t settled = keyframes > 0 ? keyframes - 1 : 0;
  if (budget_ <= 0.0) return records;
  std::vector<std::shared_ptr<const PlaceRecognition::Place>> places;
  if (next_place_ < settled) places = graph.places();
  const std::size_t end = std::min(settled, places.size());
  std::size_t piece = 0;  // the next piece to send, in pieces_
  while (piece < pieces_.size() && pieces_[piece].index < next_piece_) ++piece;
  while (budget_ > 0.0) {
    while (next_place_ < end && !places[next_place_]) ++next_place_;
    const bool place_due = next_place_ < end;
    // A piece goes once its anchor has (the merger moves it with that keyframe).
    const bool piece_due = piece < pieces_.size() &&
                           pieces_[piece].anchor < static_cast<std::int64_t>(keyframes_sent_);
    if (!place_due && !piece_due) break;
    std::string record;
    // Places first: they place the robot (and its pieces are of no use until it is).
    if (place_due) {
      record = placeRecord(run_, next_place_, *places[next_place_]);
      ++next_place_;
      ++totals_.places;
      records.push_back({Record::Kind::kPlace, std::move(record)});
    } else {
      const KeyframeStore::Entry& e = pieces_[piece];
      record = pieceRecord(run_, e);
      next_piece_ = e.index + 1;
      ++piece;
      ++totals_.pieces;
      totals_.piece_bytes += record.size();
      records.push_back({Record::Kind::kPiece, std::move(record)});
    }
    budget_ -= static_cast<double>(records.back().bytes.size());
    totals_.bytes += records.back().bytes.size();
  }
  return records;
}

std::optional<std::uint64_t> runOfRecord(const std::string& record) {
  const std::string kind = recordKind(record);
  constexpr std::size_t kHeaderBytes = 32;
  if ((kind != kStreamGraphKind && kind != kStreamPlaceKind && kind != kPieceKind) ||
      record.size() < kHeaderBytes + 8)
    return std::nullopt;
  std::uint64_t run = 0;
  std::memcpy(&run, record.data() + kHeaderBytes, sizeof run);
  return run;
}

void SessionAssembler::reset(std::uint64_t run) {
  run_ = run;
  started_ = true;
  session_ = Session{};
  places_.clear();
  pieces_.clear();
}

SessionAssembler::Result SessionAssembler::apply(const std::string& record,
                                                 const std::string& source) {
  const std::string kind = recordKind(record);
  if (kind != kStreamGraphKind && kind != kStreamPlaceKind && kind != kPieceKind)
    throw InputError(source + ": not a session record (" +
                     (kind.empty() ? std::string("no RGBDMAP header") : "kind '" + kind + "'") +
                     ")");
  if (kind == kStreamGraphKind) {
    BinaryReader in = readRecord(record, source, kStreamGraphKind, kVersion);
    return applyGraph(in);
  }
  if (kind == kStreamPlaceKind) {
    BinaryReader in = readRecord(record, source, kStreamPlaceKind, kVersion);
    return applyPlace(in);
  }
  BinaryReader in = readRecord(record, source, kPieceKind, kVersion);
  return applyPiece(in);
}

SessionAssembler::Result SessionAssembler::applyGraph(BinaryReader& in) {
  const std::uint64_t run = in.get<std::uint64_t>();
  const CameraIntrinsics camera = getCamera(in);
  const std::size_t first = in.get<std::uint64_t>();
  const std::size_t count = in.count(8 + 2 * kPoseBytes);
  std::vector<LoopCloser::Saved::Keyframe> keyframes(count);
  for (LoopCloser::Saved::Keyframe& k : keyframes) {
    k.timestamp = in.get<double>();
    k.odometry = getPose(in);
    k.pose = getPose(in);
  }
  const std::size_t first_edge = in.get<std::uint64_t>();
  const std::size_t edge_count = in.count(kEdgeBytes);
  std::vector<PoseGraph::Edge> edges;
  edges.reserve(edge_count);
  for (std::size_t i = 0; i < edge_count; ++i) edges.push_back(getEdge(in, first + count));
  if (!in.atEnd()) in.fail("corrupt (bytes after the edges)");

  Result result = Result::kApplied;
  if (!started_ || run != run_) {
    reset(run);
    result = Result::kNewRun;
  }
  auto& graph = session_.graph;
  if (first > graph.keyframes.size() || first_edge > graph.edges.size()) return Result::kGap;
  session_.camera = camera;
  // Sent again (the stream restarted): what is known already keeps its place, with the newer
  // pose estimate.
  for (std::size_t i = 0; i < count; ++i) {
    if (first + i < graph.keyframes.size())
      graph.keyframes[first + i].pose = keyframes[i].pose;
    else
      graph.keyframes.push_back(keyframes[i]);
  }
  for (std::size_t i = graph.edges.size() - first_edge; i < edges.size(); ++i)
    graph.edges.push_back(edges[i]);
  return result;
}

SessionAssembler::Result SessionAssembler::applyPlace(BinaryReader& in) {
  const std::uint64_t run = in.get<std::uint64_t>();
  const std::size_t id = in.get<std::uint64_t>();
  auto place = getPlace(in);
  if (!in.atEnd()) in.fail("corrupt (bytes after the place)");
  Result result = Result::kApplied;
  if (!started_ || run != run_) {
    reset(run);
    result = Result::kNewRun;
  }
  // Sent again: the one known stays (a place does not change once sent; the merger's comparisons
  // of it stay valid).
  places_.emplace(id, std::move(place));
  return result;
}

SessionAssembler::Result SessionAssembler::applyPiece(BinaryReader& in) {
  const std::uint64_t run = in.get<std::uint64_t>();
  KeyframeStore::Entry e;
  e.index = in.get<std::uint64_t>();
  e.timestamp = in.get<double>();
  e.anchor = in.get<std::int64_t>();
  e.pose = getPose(in);
  e.fused_at = e.pose;
  e.depth_png = getImage(in);
  e.colour_png = getImage(in);
  if (!in.atEnd()) in.fail("corrupt (bytes after the piece's images)");
  if (e.anchor < -1 || e.depth_png->empty() || e.colour_png->empty())
    in.fail("corrupt (a map piece with anchor " + std::to_string(e.anchor) + " and images of " +
            std::to_string(e.depth_png->size()) + " and " + std::to_string(e.colour_png->size()) +
            " bytes)");
  Result result = Result::kApplied;
  if (!started_ || run != run_) {
    reset(run);
    result = Result::kNewRun;
  }
  pieces_[e.index] = std::move(e);
  return result;
}

std::vector<std::string> SessionAssembler::records(
    const std::vector<KeyframeStore::Entry>& more_pieces) const {
  std::vector<std::string> records;
  if (!started_) return records;
  records.push_back(graphRecord(run_, session_.camera, AssembledGraph{session_.graph}, 0, 0));
  for (const auto& [id, place] : places_) records.push_back(placeRecord(run_, id, *place));
  for (const auto& [index, piece] : pieces_) records.push_back(pieceRecord(run_, piece));
  for (const KeyframeStore::Entry& piece : more_pieces) records.push_back(pieceRecord(run_, piece));
  return records;
}

std::vector<KeyframeStore::Entry> SessionAssembler::mapPieces() const {
  std::vector<KeyframeStore::Entry> pieces;
  pieces.reserve(pieces_.size());
  for (const auto& [index, piece] : pieces_) pieces.push_back(piece);
  return pieces;
}

Session SessionAssembler::session() const {
  Session s = session_;
  s.created_by = "rgbdmap session stream";
  s.graph.places.assign(s.graph.keyframes.size(), nullptr);
  for (const auto& [id, place] : places_)
    if (id < s.graph.places.size()) s.graph.places[id] = place;
  return s;
}

}  // namespace rgbdmap
