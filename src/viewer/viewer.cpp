#include "rgbdmap/viewer/viewer.hpp"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>
#include <vtkActor.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkIdTypeArray.h>
#include <vtkImageActor.h>
#include <vtkImageData.h>
#include <vtkImageMapper3D.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>

#include <chrono>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "rgbdmap/base/thread_name.hpp"
#include "rgbdmap/viewer/display_cloud.hpp"

namespace rgbdmap {
namespace {

// Window layout (fractions of the window): the map on the left, colour over depth on the right,
// the status bar along the bottom.
constexpr double kStatusTop = 0.05;
constexpr double kMapRight = 0.72;
constexpr double kDepthTop = 0.525;
constexpr double kFarDepth = 5.0;  // metres at the end of the depth colour ramp

const char* trackingName(TrackingState s) {
  switch (s) {
    case TrackingState::kTracked:
      return "tracking";
    case TrackingState::kLost:
      return "LOST";
    case TrackingState::kRelocalised:
      return "relocalised";
    case TrackingState::kNoPose:
      break;
  }
  return "no pose";
}

// Points (and optionally line cells through them) as VTK polydata.
void setPoints(vtkPolyData* poly, const std::vector<Eigen::Vector3f>& points,
               const std::vector<Rgb>* colors) {
  const auto n = static_cast<vtkIdType>(points.size());
  vtkNew<vtkPoints> vtk_points;
  vtk_points->SetDataTypeToFloat();
  vtk_points->SetNumberOfPoints(n);
  if (n > 0) std::memcpy(vtk_points->GetVoidPointer(0), points.data(), 3 * sizeof(float) * n);
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(n + 1);
  connectivity->SetNumberOfValues(n);
  for (vtkIdType i = 0; i < n; ++i) {
    offsets->SetValue(i, i);
    connectivity->SetValue(i, i);
  }
  offsets->SetValue(n, n);
  vtkNew<vtkCellArray> verts;
  verts->SetData(offsets, connectivity);
  poly->SetPoints(vtk_points);
  poly->SetVerts(verts);
  if (colors) {
    vtkNew<vtkUnsignedCharArray> rgb;
    rgb->SetNumberOfComponents(3);
    rgb->SetNumberOfTuples(n);
    if (n > 0) std::memcpy(rgb->GetPointer(0), colors->data(), 3 * static_cast<std::size_t>(n));
    poly->GetPointData()->SetScalars(rgb);
  }
  poly->Modified();
}

// A triangle mesh with its vertex colours as VTK polydata.
void setMesh(vtkPolyData* poly, const TriangleMesh& mesh) {
  const auto n = static_cast<vtkIdType>(mesh.vertices.size());
  vtkNew<vtkPoints> vtk_points;
  vtk_points->SetDataTypeToFloat();
  vtk_points->SetNumberOfPoints(n);
  for (vtkIdType i = 0; i < n; ++i) vtk_points->SetPoint(i, mesh.vertices[i].data());
  vtkNew<vtkCellArray> triangles;
  for (const TriangleMesh::Triangle& t : mesh.triangles) {
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    triangles->InsertNextCell(3, ids);
  }
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) rgb->SetValue(3 * i + c, mesh.colours[i][c]);
  poly->SetPoints(vtk_points);
  poly->SetPolys(triangles);
  poly->GetPointData()->SetScalars(rgb);
  poly->Modified();
}

void setPolyline(vtkPolyData* poly, const std::vector<Eigen::Vector3f>& points) {
  vtkNew<vtkPoints> vtk_points;
  for (const auto& p : points) vtk_points->InsertNextPoint(p.x(), p.y(), p.z());
  vtkNew<vtkCellArray> lines;
  lines->InsertNextCell(static_cast<vtkIdType>(points.size()));
  for (vtkIdType i = 0; i < static_cast<vtkIdType>(points.size()); ++i) lines->InsertCellPoint(i);
  poly->SetPoints(vtk_points);
  poly->SetLines(lines);
  poly->Modified();
}

// A pyramid from the camera centre to a rectangle in front of it (about a Kinect's 62 x 48
// degree field of view; the viewer does not need the exact intrinsics to show where it looks).
void setFrustum(vtkPolyData* poly, const Eigen::Isometry3d& pose) {
  constexpr double d = 0.2, x = 0.6 * d, y = 0.45 * d;
  const Eigen::Vector3d corners[5] = {{0, 0, 0}, {-x, -y, d}, {x, -y, d}, {x, y, d}, {-x, y, d}};
  vtkNew<vtkPoints> points;
  for (const auto& c : corners) {
    const Eigen::Vector3d w = pose * c;
    points->InsertNextPoint(w.x(), w.y(), w.z());
  }
  vtkNew<vtkCellArray> lines;
  const vtkIdType edges[8][2] = {{0, 1}, {0, 2}, {0, 3}, {0, 4}, {1, 2}, {2, 3}, {3, 4}, {4, 1}};
  for (const auto& e : edges) lines->InsertNextCell(2, e);
  poly->SetPoints(points);
  poly->SetLines(lines);
  poly->Modified();
}

vtkSmartPointer<vtkActor> makeActor(vtkPolyData* poly, double r, double g, double b, float size,
                                    bool scalars) {
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetScalarVisibility(scalars);
  if (scalars) mapper->SetColorModeToDirectScalars();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(r, g, b);
  actor->GetProperty()->SetPointSize(size);
  actor->GetProperty()->SetLineWidth(size);
  actor->GetProperty()->SetLighting(false);  // points have no normals: show their own colours
  return actor;
}

// An image pane: a 2D renderer with one image actor, filled from an OpenCV BGR image.
class ImagePane {
 public:
  ImagePane(vtkRenderWindow* window, double x0, double y0, double x1, double y1) {
    renderer_->SetViewport(x0, y0, x1, y1);
    renderer_->SetBackground(0.05, 0.05, 0.05);
    renderer_->SetInteractive(false);
    actor_->GetMapper()->SetInputData(image_);
    renderer_->AddActor(actor_);
    window->AddRenderer(renderer_);
  }
  void show(const cv::Mat& bgr) {
    int* dims = image_->GetDimensions();
    const bool resized = dims[0] != bgr.cols || dims[1] != bgr.rows;
    if (resized) {
      image_->SetDimensions(bgr.cols, bgr.rows, 1);
      image_->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
    }
    cv::cvtColor(bgr, rgb_, cv::COLOR_BGR2RGB);
    // VTK's first row is the bottom one.
    cv::Mat target(bgr.rows, bgr.cols, CV_8UC3, image_->GetScalarPointer());
    cv::flip(rgb_, target, 0);
    image_->Modified();
    if (resized) {
      renderer_->ResetCamera();
      renderer_->GetActiveCamera()->ParallelProjectionOn();
      renderer_->ResetCamera();
      renderer_->GetActiveCamera()->SetParallelScale(0.5 * bgr.rows);
    }
  }

 private:
  vtkNew<vtkRenderer> renderer_;
  vtkNew<vtkImageData> image_;
  vtkNew<vtkImageActor> actor_;
  cv::Mat rgb_;
};

// Everything in the window, owned and touched by the viewer thread only.
class Scene {
 public:
  explicit Scene(const ViewerOptions& options)
      : options_(options),
        follow_(options.follow),
        color_pane_(window_, kMapRight, kDepthTop, 1.0, 1.0),
        depth_pane_(window_, kMapRight, kStatusTop, 1.0, kDepthTop) {
    window_->SetWindowName(options.title.c_str());
    window_->SetSize(options.width, options.height);

    map_renderer_->SetViewport(0.0, kStatusTop, 1.0, 1.0);
    map_renderer_->SetBackground(0.12, 0.12, 0.14);
    map_actor_ = makeActor(map_, 1, 1, 1, 2.0f, true);
    trajectory_actor_ = makeActor(trajectory_, 1.0, 0.55, 0.0, 2.0f, false);
    keyframe_actor_ = makeActor(keyframes_, 1.0, 0.9, 0.2, 6.0f, false);
    frustum_actor_ = makeActor(frustum_, 0.2, 1.0, 0.3, 2.0f, false);
    mesh_actor_ = makeActor(mesh_, 1, 1, 1, 1.0f, true);
    mesh_actor_->GetProperty()->SetLighting(true);  // shaded faces show the shape
    map_renderer_->AddActor(mesh_actor_);
    for (vtkActor* a :
         {map_actor_.Get(), trajectory_actor_.Get(), keyframe_actor_.Get(), frustum_actor_.Get()})
      map_renderer_->AddActor(a);
    window_->AddRenderer(map_renderer_);

    status_renderer_->SetViewport(0.0, 0.0, 1.0, kStatusTop);
    status_renderer_->SetBackground(0.02, 0.02, 0.02);
    status_renderer_->SetInteractive(false);
    status_text_->GetTextProperty()->SetFontSize(14);
    status_text_->GetTextProperty()->SetColor(0.9, 0.9, 0.9);
    status_text_->SetPosition(8, 8);
    status_renderer_->AddActor2D(status_text_);
    window_->AddRenderer(status_renderer_);

    interactor_->SetRenderWindow(window_);
    interactor_->SetInteractorStyle(style_);
    // Ahead of the interactor style (priority 0), which has its own meaning for s, f, q, e.
    keys_->SetCallback(&Scene::onKey);
    keys_->SetClientData(this);
    interactor_->AddObserver(vtkCommand::CharEvent, keys_, 1.0);
    exit_->SetCallback(&Scene::onExit);
    exit_->SetClientData(this);
    interactor_->AddObserver(vtkCommand::ExitEvent, exit_, 1.0);
    interactor_->Initialize();
    updateStatus();
    window_->Render();
  }

  ~Scene() { window_->Finalize(); }

  bool closed() const { return closed_; }
  bool mapShown() const { return map_shown_; }
  void processEvents() { interactor_->ProcessEvents(); }

  void apply(const ViewerUpdate& u) {
    if (u.has_images) {
      // The map takes the whole width until there are images to show beside it.
      map_renderer_->SetViewport(0.0, kStatusTop, kMapRight, 1.0);
      color_pane_.show(u.color);
      cv::Mat scaled;
      u.depth.convertTo(scaled, CV_8U, 255.0 / kFarDepth);
      cv::applyColorMap(scaled, depth_bgr_, cv::COLORMAP_TURBO);
      depth_bgr_.setTo(cv::Scalar::all(0), u.depth <= 0);
      depth_pane_.show(depth_bgr_);
    }
    if (!u.new_points.empty()) {
      for (const TrajectoryPoint& p : u.new_points) {
        trajectory_points_.push_back(p.position.cast<float>());
        if (p.keyframe) keyframe_points_.push_back(p.position.cast<float>());
      }
      if (trajectory_points_.size() >= 2) setPolyline(trajectory_, trajectory_points_);
      setPoints(keyframes_, keyframe_points_, nullptr);
    }
    if (u.has_pose) {
      if (!has_up_) {
        // "Up" is where the first camera's image up pointed (TUM axes: y down).
        up_ = -(u.pose.linear() * Eigen::Vector3d::UnitY()).cast<float>();
        has_up_ = true;
      }
      pose_ = u.pose;
      has_pose_ = true;
      setFrustum(frustum_, pose_);
    }
    if (u.has_status) {
      live_ = true;
      status_ = u.status;
      const double t = seconds();
      if (t - fps_since_ >= 1.0) {
        fps_ = static_cast<double>(status_.frames_processed - fps_frames_) / (t - fps_since_);
        fps_since_ = t;
        fps_frames_ = status_.frames_processed;
      }
      const bool lost = status_.tracking == TrackingState::kLost;
      frustum_actor_->GetProperty()->SetColor(lost ? 1.0 : 0.2, lost ? 0.2 : 1.0, 0.3);
    }
    if (u.map) {
      cloud_.assign(*u.map, options_.max_points);
      drawCloud();
      if (!options_.follow && !map_shown_) {
        // Look the way the first camera looked, then back off until the whole map is in view.
        if (has_pose_) followCamera();
        map_renderer_->ResetCamera();
      }
    }
    if (u.mesh) {
      setMesh(mesh_, *u.mesh);
      mesh_triangles_ = u.mesh->triangles.size();
      if (!options_.follow && !map_shown_) {
        if (has_pose_) followCamera();
        map_renderer_->ResetCamera();
      }
    }
    if (follow_ && has_pose_) followCamera();
    updateStatus();
    dirty_ = true;
  }

  void render() {
    if (!dirty_) return;
    dirty_ = false;
    map_renderer_->ResetCameraClippingRange();
    window_->Render();
    if (!announce_.empty()) {
      spdlog::info("viewer: on screen: {}", announce_);  // after drawing: tests wait for it
      announce_.clear();
    }
    if (!map_shown_ && mesh_triangles_ > 0) {
      map_shown_ = true;
      spdlog::info("viewer: map on screen (a mesh of {} triangles)", mesh_triangles_);
    }
    if (!map_shown_ && !cloud_.points.empty()) {
      map_shown_ = true;
      spdlog::info("viewer: map on screen ({} of {} points drawn)", cloud_.points.size(),
                   cloud_.map_points);
    }
  }

 private:
  static double seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  void drawCloud() {
    if (by_height_) {
      const std::vector<Rgb> colors = heightColors(cloud_.points, up_);
      setPoints(map_, cloud_.points, &colors);
    } else {
      setPoints(map_, cloud_.points, &cloud_.colors);
    }
  }

  // Behind and above the camera, looking where it looks.
  void followCamera() {
    vtkCamera* camera = map_renderer_->GetActiveCamera();
    const Eigen::Vector3d eye = pose_ * Eigen::Vector3d(0, -0.6, -2.0);
    const Eigen::Vector3d target = pose_ * Eigen::Vector3d(0, 0, 1.5);
    const Eigen::Vector3d up = pose_.linear() * Eigen::Vector3d(0, -1, 0);
    camera->SetPosition(eye.x(), eye.y(), eye.z());
    camera->SetFocalPoint(target.x(), target.y(), target.z());
    camera->SetViewUp(up.x(), up.y(), up.z());
    camera->SetViewAngle(50.0);  // wide enough for what a Kinect sees from 2 m behind it
  }

  void updateStatus() {
    const std::string drawn = cloud_.points.size() < cloud_.map_points
                                  ? " (" + std::to_string(cloud_.points.size()) + " drawn)"
                                  : std::string();
    const std::string view = std::string(" | view ") + (follow_ ? "follow" : "free") + ", colour " +
                             (by_height_ ? "height" : "rgb") +
                             " | keys: s snapshot, q quit, f follow, c colour";
    char line[512];
    if (live_) {
      std::snprintf(line, sizeof line,
                    "%s%s%.1f fps | frames %llu | keyframes %llu | map %llu points%s | "
                    "dropped %llu | %s%s",
                    options_.caption.c_str(), options_.caption.empty() ? "" : " | ", fps_,
                    static_cast<unsigned long long>(status_.frames_processed),
                    static_cast<unsigned long long>(status_.keyframes),
                    static_cast<unsigned long long>(
                        std::max<std::uint64_t>(status_.map_points, cloud_.map_points)),
                    drawn.c_str(), static_cast<unsigned long long>(status_.frames_dropped),
                    trackingName(status_.tracking), view.c_str());
    } else {
      std::snprintf(line, sizeof line, "%s%smap %zu points%s | keyframes %zu%s",
                    options_.caption.c_str(), options_.caption.empty() ? "" : " | ",
                    cloud_.map_points, drawn.c_str(), keyframe_points_.size(), view.c_str());
    }
    status_text_->SetInput(line);
  }

  static void onKey(vtkObject*, unsigned long, void* client, void*) {
    auto* self = static_cast<Scene*>(client);
    switch (self->interactor_->GetKeyCode()) {
      case 's':
        spdlog::info("viewer: s pressed: writing a snapshot");
        if (self->options_.on_snapshot) self->options_.on_snapshot();
        break;
      case 'q':
        spdlog::info("viewer: q pressed: stopping and saving");
        self->stop();
        break;
      case 'f':
        self->follow_ = !self->follow_;
        if (self->follow_ && self->has_pose_) self->followCamera();
        self->announce_ = self->follow_ ? "view follows the camera" : "view free";
        break;
      case 'c':
        self->by_height_ = !self->by_height_;
        self->drawCloud();
        self->announce_ = self->by_height_ ? "colour by height" : "colour rgb";
        break;
      default:
        return;  // the interactor style's keys (r resets the view, ...)
    }
    self->keys_->SetAbortFlag(1);
    self->updateStatus();
    self->dirty_ = true;
  }

  static void onExit(vtkObject*, unsigned long, void* client, void*) {
    auto* self = static_cast<Scene*>(client);
    if (self->closed_) return;
    spdlog::info("viewer: window closed: stopping and saving");
    self->stop();
  }

  void stop() {
    closed_ = true;
    if (options_.on_stop) options_.on_stop();
  }

  const ViewerOptions& options_;
  vtkNew<vtkRenderWindow> window_;
  vtkNew<vtkRenderWindowInteractor> interactor_;
  vtkNew<vtkInteractorStyleTrackballCamera> style_;
  vtkNew<vtkCallbackCommand> keys_;
  vtkNew<vtkCallbackCommand> exit_;
  vtkNew<vtkRenderer> map_renderer_;
  vtkNew<vtkRenderer> status_renderer_;
  vtkNew<vtkTextActor> status_text_;
  vtkNew<vtkPolyData> map_, trajectory_, keyframes_, frustum_, mesh_;
  vtkSmartPointer<vtkActor> map_actor_, trajectory_actor_, keyframe_actor_, frustum_actor_,
      mesh_actor_;
  std::size_t mesh_triangles_ = 0;
  bool follow_;
  ImagePane color_pane_;
  ImagePane depth_pane_;
  cv::Mat depth_bgr_;

  DisplayCloud cloud_;
  std::vector<Eigen::Vector3f> trajectory_points_, keyframe_points_;
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  bool has_pose_ = false;
  Eigen::Vector3f up_ = -Eigen::Vector3f::UnitY();
  bool has_up_ = false;
  bool by_height_ = false;
  PublishedStatus status_;
  double fps_ = 0.0, fps_since_ = seconds();
  std::uint64_t fps_frames_ = 0;
  std::string announce_;  // logged once the window shows it
  bool live_ = false;     // a mapping run publishes its status; a saved map does not
  bool closed_ = false;
  bool dirty_ = true;
  bool map_shown_ = false;
};

}  // namespace

Viewer::Viewer(ViewerOptions options) : options_(std::move(options)) {
  thread_ = std::thread([this] { run(); });
}

Viewer::~Viewer() { close(); }

void Viewer::close() {
  close_requested_.store(true);
  if (thread_.joinable()) thread_.join();
}

void Viewer::waitUntilClosed() {
  if (thread_.joinable()) thread_.join();
}

void Viewer::run() {
  nameThisThread("rgbdmap-viewer");
  // Drawing yields the CPU to mapping; Mesa's software rasteriser threads, started from this
  // thread, inherit the niceness.
  if (options_.nice > 0) ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), options_.nice);
  try {
    Scene scene(options_);
    spdlog::info("viewer: window open ({}x{})", options_.width, options_.height);
    const auto tick = std::chrono::duration<double>(1.0 / options_.refresh_hz);
    ViewerUpdate update;
    auto next = std::chrono::steady_clock::now();
    while (!close_requested_.load() && !scene.closed()) {
      scene.processEvents();
      if (mailbox_.take(update)) scene.apply(update);
      scene.render();
      // A slow display only lowers this loop's rate: publishers never wait for it.
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(tick);
      const auto now = std::chrono::steady_clock::now();
      if (next < now) next = now;
      std::this_thread::sleep_until(next);
    }
  } catch (const std::exception& e) {
    spdlog::error("viewer: {}; mapping goes on without it", e.what());
  }
}

}  // namespace rgbdmap
