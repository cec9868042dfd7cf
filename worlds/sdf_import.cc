#include "worlds/sdf_import.h"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>
#include <system_error>
#include <utility>

#include <sdf/Actor.hh>
#include <sdf/Box.hh>
#include <sdf/Collision.hh>
#include <sdf/Console.hh>
#include <sdf/Cylinder.hh>
#include <sdf/Ellipsoid.hh>
#include <sdf/Geometry.hh>
#include <sdf/Link.hh>
#include <sdf/Mesh.hh>
#include <sdf/Model.hh>
#include <sdf/ParserConfig.hh>
#include <sdf/Plane.hh>
#include <sdf/Root.hh>
#include <sdf/SDFImpl.hh>
#include <sdf/Sphere.hh>
#include <sdf/Visual.hh>
#include <sdf/World.hh>

#include "worlds/mesh_import.h"
#include "worlds/movers.h"
#include "worlds/number_text.h"
#include "worlds/obj_import.h"
#include "worlds/placement.h"
#include "worlds/primitives.h"

namespace enavi::worlds {
namespace {

constexpr double kPadding = 2.0;   // m around the geometry, as for a mesh world
constexpr double kUpright = 1e-9;  // |sin| of a tilt still taken as upright
// Gazebo plays an actor's trajectories one after the other, jumping to the next one's first
// pose; a mover's waypoint times must increase, so the jump takes this long.
constexpr double kTrajectoryJump = 1e-3;  // s

// The two models nearly every Gazebo world includes, written as Gazebo's own model database
// defines them (ground_plane: a static 100 m x 100 m plane, normal +z; sun: a directional
// light), so that a world needs no model path for them.
constexpr const char* kGroundPlaneSdf = R"(<?xml version="1.0"?>
<sdf version="1.6"><model name="ground_plane"><static>true</static><link name="link">
<collision name="collision"><geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry></collision>
</link></model></sdf>
)";
constexpr const char* kSunSdf = R"(<?xml version="1.0"?>
<sdf version="1.6"><light type="directional" name="sun"><cast_shadows>true</cast_shadows><pose>0 0 10 0 0 0</pose>
<diffuse>0.8 0.8 0.8 1</diffuse><specular>0.2 0.2 0.2 1</specular><direction>-0.5 0.1 -0.9</direction></light></sdf>
)";

// A scratch model directory holding the built-in models, removed when the load is done.
class BuiltinModels {
 public:
  BuiltinModels() {
    static std::atomic<int> counter{0};
    dir_ = std::filesystem::temp_directory_path() /
           ("enavi-sdf-models-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    Write("ground_plane", kGroundPlaneSdf);
    Write("sun", kSunSdf);
  }
  ~BuiltinModels() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  BuiltinModels(const BuiltinModels&) = delete;
  BuiltinModels& operator=(const BuiltinModels&) = delete;
  const std::filesystem::path& dir() const { return dir_; }

 private:
  void Write(const std::string& name, const char* sdf) {
    const auto model = dir_ / name;
    std::filesystem::create_directories(model);
    std::ofstream(model / "model.config") << "<?xml version=\"1.0\"?>\n<model><name>" << name
                                          << "</name><version>1.0</version><sdf version=\"1.6\">model.sdf</sdf></model>\n";
    std::ofstream(model / "model.sdf") << sdf;
  }
  std::filesystem::path dir_;
};

Eigen::Isometry3d ToEigen(const ignition::math::Pose3d& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(p.Pos().X(), p.Pos().Y(), p.Pos().Z());
  X.linear() = Eigen::Quaterniond(p.Rot().W(), p.Rot().X(), p.Rot().Y(), p.Rot().Z()).normalized().toRotationMatrix();
  return X;
}

std::string Join(const std::vector<std::string>& items, const std::string& sep = ", ") {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : sep) + s;
  return out;
}

class SdfReader {
 public:
  SdfReader(std::string file, std::vector<std::filesystem::path> model_dirs)
      : file_(std::move(file)), model_dirs_(std::move(model_dirs)) {}

  void ReadWorld(const sdf::World& world) {
    if (world.LightCount() > 0) ignored_.push_back(std::to_string(world.LightCount()) + " light(s)");
    if (world.Element() && world.Element()->HasElement("physics")) ignored_.push_back("physics settings");
    CountPlugins(world.Element());
    for (uint64_t i = 0; i < world.ModelCount(); ++i) {
      const sdf::Model& model = *world.ModelByIndex(i);
      ignition::math::Pose3d pose;
      Check(model.SemanticPose().Resolve(pose), "model '" + model.Name() + "'");
      ReadModel(model, ToEigen(pose), model.Name(), model.Static());
    }
    for (uint64_t i = 0; i < world.ActorCount(); ++i) ReadActor(*world.ActorByIndex(i));
  }

  std::vector<Mover>& movers() { return movers_; }

  std::vector<Object>& objects() { return objects_; }
  const Ground& ground() const { return ground_; }
  std::string Note() const {
    std::vector<std::string> all = ignored_;
    if (plugins_ > 0) all.push_back(std::to_string(plugins_) + " plugin(s)");
    if (!dynamic_.empty()) all.push_back("non-static model(s) " + Join(dynamic_));
    if (!animations_.empty()) all.push_back("skeleton animation of actor(s) " + Join(animations_) + " (their skin moves rigidly)");
    if (!waiting_.empty()) all.push_back("actor(s) " + Join(waiting_) + " without <auto_start> (they stand still)");
    return all.empty() ? "" : "SDF: ignored " + Join(all, "; ");
  }

 private:
  void CountPlugins(const sdf::ElementPtr& e) {
    if (!e) return;
    for (auto child = e->GetFirstElement(); child; child = child->GetNextElement()) {
      if (child->GetName() == "plugin") ++plugins_;
      else CountPlugins(child);
    }
  }

  void Check(const sdf::Errors& errors, const std::string& what) const {
    if (!errors.empty()) throw WorldError(file_, 0, what, errors.front().Message());
  }

  // A model's links and nested models; `is_static` passes down (a nested model of a static
  // model is static too).
  void ReadModel(const sdf::Model& model, const Eigen::Isometry3d& X_WM, const std::string& scope, bool is_static) {
    is_static = is_static || model.Static();
    if (!is_static) {
      dynamic_.push_back("'" + scope + "'");
      return;
    }
    for (uint64_t i = 0; i < model.LinkCount(); ++i) {
      const sdf::Link& link = *model.LinkByIndex(i);
      const std::string where = "model '" + scope + "' link '" + link.Name() + "'";
      if (link.CollisionCount() > 0) {
        for (uint64_t c = 0; c < link.CollisionCount(); ++c) {
          const sdf::Collision& col = *link.CollisionByIndex(c);
          ignition::math::Pose3d pose;
          Check(col.SemanticPose().Resolve(pose, "__model__"), where);
          ReadGeometry(*col.Geom(), X_WM * ToEigen(pose), where + " collision '" + col.Name() + "'");
        }
      } else {
        for (uint64_t v = 0; v < link.VisualCount(); ++v) {
          const sdf::Visual& vis = *link.VisualByIndex(v);
          ignition::math::Pose3d pose;
          Check(vis.SemanticPose().Resolve(pose, "__model__"), where);
          ReadGeometry(*vis.Geom(), X_WM * ToEigen(pose), where + " visual '" + vis.Name() + "'");
        }
      }
    }
    for (uint64_t i = 0; i < model.ModelCount(); ++i) {
      const sdf::Model& nested = *model.ModelByIndex(i);
      ignition::math::Pose3d pose;
      Check(nested.SemanticPose().Resolve(pose, "__model__"), "model '" + scope + "::" + nested.Name() + "'");
      ReadModel(nested, X_WM * ToEigen(pose), scope + "::" + nested.Name(), is_static);
    }
  }

  // An actor (Gazebo's scripted, animated model): its links' geometry, else its skin mesh, in
  // its own frame; with a scripted trajectory it is a timed mover, else it stands at its pose.
  // Waypoint poses are world poses, as Gazebo places the actor along them (yaw kept; an actor
  // is upright). Trajectories play one after the other; <loop> repeats them, <delay_start> waits.
  void ReadActor(const sdf::Actor& actor) {
    const std::string where = "actor '" + actor.Name() + "'";
    std::vector<Object> shape;
    std::swap(shape, objects_);  // ReadGeometry adds to objects_: collect the actor's own
    for (uint64_t i = 0; i < actor.LinkCount(); ++i) {
      const sdf::Link& link = *actor.LinkByIndex(i);
      const Eigen::Isometry3d X_AL = ToEigen(link.RawPose());
      const std::string at = where + " link '" + link.Name() + "'";
      if (link.CollisionCount() > 0) {
        for (uint64_t c = 0; c < link.CollisionCount(); ++c) {
          const sdf::Collision& col = *link.CollisionByIndex(c);
          ReadGeometry(*col.Geom(), X_AL * ToEigen(col.RawPose()), at + " collision '" + col.Name() + "'");
        }
      } else {
        for (uint64_t v = 0; v < link.VisualCount(); ++v) {
          const sdf::Visual& vis = *link.VisualByIndex(v);
          ReadGeometry(*vis.Geom(), X_AL * ToEigen(vis.RawPose()), at + " visual '" + vis.Name() + "'");
        }
      }
    }
    // sdformat reads an absent <skin> as the file name "__default__".
    const bool has_skin = !actor.SkinFilename().empty() && actor.SkinFilename() != "__default__";
    if (objects_.empty() && has_skin) {
      const std::filesystem::path path = ResolveMeshUri(actor.SkinFilename(), actor.FilePath(), where + " skin");
      const MeshObject placed = PlaceMesh(LoadMeshFile(path), {}, "", path.string());
      ImportedMesh skin;
      skin.triangles = placed.mesh.triangles;
      for (const auto& v : placed.mesh.vertices) skin.vertices.push_back(actor.SkinScale() * (placed.offset + v.cast<double>()));
      AddPosed(std::move(skin));
    }
    std::swap(shape, objects_);
    if (shape.empty()) throw WorldError(file_, 0, where, "has neither links with geometry nor a <skin>: nothing to see or hit");
    if (actor.AnimationCount() > 0) animations_.push_back("'" + actor.Name() + "'");

    Mover mover;
    mover.name = actor.Name();
    double offset = 0.0;
    for (uint64_t i = 0; i < actor.TrajectoryCount(); ++i) {
      const sdf::Trajectory& trajectory = *actor.TrajectoryByIndex(i);
      for (uint64_t k = 0; k < trajectory.WaypointCount(); ++k) {
        const sdf::Waypoint& w = *trajectory.WaypointByIndex(k);
        MoverWaypoint point;
        const Eigen::Isometry3d X = ToEigen(w.Pose());
        point.position = X.translation();
        point.yaw = std::atan2(X.linear()(1, 0), X.linear()(0, 0));
        point.t = offset + w.Time();
        if (!mover.waypoints.empty() && !(point.t > mover.waypoints.back().t)) {
          if (k > 0) {
            throw WorldError(file_, 0, where + " trajectory " + std::to_string(trajectory.Id()),
                             "waypoint times must increase (" + FormatFixed(w.Time()) + " s follows an equal or later one)");
          }
          point.t = mover.waypoints.back().t + kTrajectoryJump;
        }
        mover.waypoints.push_back(point);
      }
      if (!mover.waypoints.empty()) offset = mover.waypoints.back().t;
    }
    const Eigen::Isometry3d X_WA = ToEigen(actor.RawPose());
    if (mover.waypoints.size() < 2) {
      // No trajectory to follow: it stands where it is posed (with the one waypoint's pose, if any).
      const Eigen::Isometry3d X = mover.waypoints.empty() ? X_WA : ToEigen(actor.TrajectoryByIndex(0)->WaypointByIndex(0)->Pose());
      for (const Object& o : shape) AddPosedMesh(ObjectMesh(o), X, Eigen::Vector3d::Ones());
      return;
    }
    mover.shape = std::move(shape);
    mover.mode = actor.ScriptLoop() ? MoverMode::kLoop : MoverMode::kOnce;
    mover.start_delay = actor.ScriptDelayStart();
    if (!actor.ScriptAutoStart()) {
      mover.start_delay = 86'400.0;  // started by a plugin in Gazebo; here, never
      waiting_.push_back("'" + actor.Name() + "'");
    }
    movers_.push_back(std::move(mover));
  }

  static bool TurnedOnlyAboutZ(const Eigen::Isometry3d& X) {
    const Eigen::Matrix3d R = X.linear();
    return std::abs(R(2, 0)) < kUpright && std::abs(R(2, 1)) < kUpright && std::abs(R(0, 2)) < kUpright &&
           std::abs(R(1, 2)) < kUpright;
  }
  static bool AxisVertical(const Eigen::Isometry3d& X) {
    const Eigen::Vector3d z = X.linear().col(2);
    return std::abs(z.x()) < kUpright && std::abs(z.y()) < kUpright;
  }

  // Geometry in its own frame posed by X_WG, as a triangle mesh in the world frame.
  void AddPosedMesh(const TriangleMesh& local, const Eigen::Isometry3d& X_WG, const Eigen::Vector3d& scale) {
    ImportedMesh posed;
    posed.triangles = local.triangles;
    posed.vertices.reserve(local.vertices.size());
    for (const auto& v : local.vertices) posed.vertices.push_back(X_WG * v.cast<double>().cwiseProduct(scale));
    AddPosed(std::move(posed));
  }
  void AddPosed(ImportedMesh posed) {
    MeshPlacement upright;
    upright.up = UpAxis::kZ;
    objects_.emplace_back(PlaceMesh(posed, upright, "", file_));
  }

  void ReadGeometry(const sdf::Geometry& geom, const Eigen::Isometry3d& X_WG, const std::string& where) {
    switch (geom.Type()) {
      case sdf::GeometryType::EMPTY:
        return;
      case sdf::GeometryType::BOX: {
        Box box;
        const auto& s = geom.BoxShape()->Size();
        box.size = Eigen::Vector3d(s.X(), s.Y(), s.Z());
        if (TurnedOnlyAboutZ(X_WG)) {
          box.center = X_WG.translation();
          box.yaw = std::atan2(X_WG.linear()(1, 0), X_WG.linear()(0, 0));
          objects_.emplace_back(box);
        } else {
          AddPosedMesh(ObjectMesh(box), X_WG, Eigen::Vector3d::Ones());
        }
        return;
      }
      case sdf::GeometryType::CYLINDER: {
        Cylinder cyl;
        cyl.radius = geom.CylinderShape()->Radius();
        cyl.height = geom.CylinderShape()->Length();
        if (AxisVertical(X_WG)) {
          cyl.base = X_WG.translation() - Eigen::Vector3d(0, 0, 0.5 * cyl.height);
          objects_.emplace_back(cyl);
        } else {
          cyl.base = Eigen::Vector3d(0, 0, -0.5 * cyl.height);  // SDF cylinders are centred on their frame
          AddPosedMesh(ObjectMesh(cyl), X_WG, Eigen::Vector3d::Ones());
        }
        return;
      }
      case sdf::GeometryType::SPHERE: {
        Ellipsoid e;
        e.center = X_WG.translation();
        e.radii = Eigen::Vector3d::Constant(geom.SphereShape()->Radius());
        objects_.emplace_back(e);
        return;
      }
      case sdf::GeometryType::ELLIPSOID: {
        const auto& r = geom.EllipsoidShape()->Radii();
        Ellipsoid e;
        e.radii = Eigen::Vector3d(r.X(), r.Y(), r.Z());
        if (TurnedOnlyAboutZ(X_WG) && std::abs(X_WG.linear()(0, 1)) < kUpright) {
          e.center = X_WG.translation();
          objects_.emplace_back(e);
        } else {
          AddPosedMesh(ObjectMesh(e), X_WG, Eigen::Vector3d::Ones());
        }
        return;
      }
      case sdf::GeometryType::PLANE: {
        const auto& n = geom.PlaneShape()->Normal();
        const Eigen::Vector3d normal_W = X_WG.linear() * Eigen::Vector3d(n.X(), n.Y(), n.Z()).normalized();
        if (!ground_.enabled && std::abs(normal_W.x()) < kUpright && std::abs(normal_W.y()) < kUpright &&
            normal_W.z() > 0.0) {
          ground_.enabled = true;
          ground_.z = X_WG.translation().z();
          return;
        }
        // Any other plane: its finite <size> as a quad.
        const auto& size = geom.PlaneShape()->Size();
        const Eigen::Vector3d n_G = Eigen::Vector3d(n.X(), n.Y(), n.Z()).normalized();
        const Eigen::Vector3d u = n_G.unitOrthogonal(), w = n_G.cross(u);
        TriangleMesh quad;
        for (const double a : {-0.5, 0.5}) {
          for (const double b : {-0.5, 0.5}) quad.vertices.push_back((a * size.X() * u + b * size.Y() * w).cast<float>());
        }
        quad.triangles = {{0, 2, 3}, {0, 3, 1}};
        AddPosedMesh(quad, X_WG, Eigen::Vector3d::Ones());
        return;
      }
      case sdf::GeometryType::MESH: {
        const sdf::Mesh& mesh = *geom.MeshShape();
        if (!mesh.Submesh().empty()) {
          throw WorldError(file_, 0, where, "mesh submesh '" + mesh.Submesh() + "' is not supported (use the whole mesh)");
        }
        const std::filesystem::path path = ResolveMeshUri(mesh.Uri(), mesh.FilePath(), where);
        const MeshObject placed = PlaceMesh(LoadMeshFile(path), {}, "", path.string());
        const auto& s = mesh.Scale();
        const Eigen::Vector3d scale(s.X(), s.Y(), s.Z());
        if (!(scale.minCoeff() > 0.0)) throw WorldError(file_, 0, where, "mesh scale must be positive");
        ImportedMesh posed;
        posed.triangles = placed.mesh.triangles;
        for (const auto& v : placed.mesh.vertices) {
          posed.vertices.push_back(X_WG * (placed.offset + v.cast<double>()).cwiseProduct(scale));
        }
        AddPosed(std::move(posed));
        return;
      }
      default:
        throw WorldError(file_, 0, where,
                         "geometry type not supported (supported: box, cylinder, sphere, ellipsoid, plane, mesh)");
    }
  }

  // model://NAME/rest against the model path, file:// and plain paths against the SDF file
  // that holds the mesh.
  std::filesystem::path ResolveMeshUri(const std::string& uri, const std::string& sdf_file,
                                       const std::string& where) const {
    const std::string model_scheme = "model://", file_scheme = "file://";
    if (uri.rfind(model_scheme, 0) == 0) {
      const std::string rest = uri.substr(model_scheme.size());
      for (const auto& dir : model_dirs_) {
        const auto candidate = dir / rest;
        if (std::filesystem::is_regular_file(candidate)) return candidate;
      }
      throw WorldError(file_, 0, where, "mesh " + uri + " not found (searched: " + SearchedDirs() + ")");
    }
    std::filesystem::path p = uri.rfind(file_scheme, 0) == 0 ? std::filesystem::path(uri.substr(file_scheme.size()))
                                                             : std::filesystem::path(uri);
    if (p.is_relative()) p = std::filesystem::path(sdf_file.empty() ? file_ : sdf_file).parent_path() / p;
    if (!std::filesystem::is_regular_file(p)) throw WorldError(file_, 0, where, "mesh " + uri + " not found (" + p.string() + ")");
    return p;
  }

 public:
  std::string SearchedDirs() const {
    std::vector<std::string> dirs;
    for (const auto& d : model_dirs_) dirs.push_back(d.string());
    return dirs.empty() ? "no --model-path and no GAZEBO_MODEL_PATH" : Join(dirs);
  }

 private:
  std::string file_;
  std::vector<std::filesystem::path> model_dirs_;
  std::vector<Object> objects_;
  Ground ground_{false, 0.0};
  std::vector<Mover> movers_;
  std::vector<std::string> ignored_, dynamic_, animations_, waiting_;
  int plugins_ = 0;
};

}  // namespace

bool IsSdfFile(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
  return ext == ".sdf" || ext == ".world";
}

World LoadSdfWorld(const std::filesystem::path& path, const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                   const std::vector<std::filesystem::path>& model_path) {
  const std::string name = path.string();
  CheckInputFile(path);

  // Model directories: the caller's, then GAZEBO_MODEL_PATH, then the built-in two.
  std::vector<std::filesystem::path> dirs = model_path;
  if (const char* env = std::getenv("GAZEBO_MODEL_PATH"); env != nullptr) {
    std::string list = env;
    for (std::size_t pos = 0; pos <= list.size();) {
      const std::size_t colon = std::min(list.find(':', pos), list.size());
      if (colon > pos) dirs.emplace_back(list.substr(pos, colon - pos));
      pos = colon + 1;
    }
  }
  const BuiltinModels builtin;
  std::vector<std::filesystem::path> search = dirs;
  search.push_back(builtin.dir());

  // libsdformat prints its errors to the console; they come back as the exception below.
  sdf::Console::Instance()->SetQuiet(true);
  sdf::ParserConfig config;
  for (const auto& d : search) config.AddURIPath("model://", d.string());
  std::set<std::string> missing;
  config.SetFindCallback([&missing](const std::string& uri) {
    missing.insert(uri);
    return std::string();
  });
  sdf::Root root;
  const sdf::Errors errors = root.Load(name, config);
  SdfReader reader(name, dirs);
  if (!missing.empty()) {
    throw WorldError(name, 0, "include",
                     *missing.begin() + " not found: give its directory with --model-path or GAZEBO_MODEL_PATH (searched: " +
                         reader.SearchedDirs() + ")");
  }
  if (!errors.empty()) {
    const sdf::Error& e = errors.front();
    throw WorldError(e.FilePath().value_or(name), e.LineNumber().value_or(0), "sdf", e.Message());
  }
  if (root.WorldCount() == 0) throw WorldError(name, 0, "world", "no <world> in the file (an SDF world is needed)");
  reader.ReadWorld(*root.WorldByIndex(0));

  World world;
  world.objects = std::move(reader.objects());
  world.movers = std::move(reader.movers());
  world.ground = reader.ground();
  Eigen::AlignedBox3d geometry;
  for (const auto& o : world.objects) geometry.extend(ObjectBounds(o));
  // Movers: their shapes wherever their waypoints take them (turned any way about z).
  for (const Mover& m : world.movers) {
    Eigen::AlignedBox3d shape;
    for (const auto& o : m.shape) shape.extend(ObjectBounds(o));
    const double r = std::max(shape.min().head<2>().norm(), shape.max().head<2>().norm());
    for (const MoverWaypoint& w : m.waypoints) {
      geometry.extend(w.position + Eigen::Vector3d(-r, -r, shape.min().z()));
      geometry.extend(w.position + Eigen::Vector3d(r, r, shape.max().z()));
    }
  }
  if (geometry.isEmpty()) geometry.extend(start);
  world.bounds = PaddedBounds(geometry, start, goal, kPadding, name);
  if (world.ground.enabled && world.bounds.min().z() < world.ground.z) {
    world.bounds.min().z() = world.ground.z;
  }
  if (!(world.bounds.max().z() > world.bounds.min().z() + 1.0)) {
    throw WorldError(name, 0, "bounds", "nothing above the ground to fly in (start and goal below it?)");
  }
  world.start = start;
  world.goal = goal;
  world.metadata.name = root.WorldByIndex(0)->Name().empty() ? path.stem().string() : root.WorldByIndex(0)->Name();
  world.metadata.scenario = "custom";
  world.metadata.import_note = reader.Note();
  return world;
}

}  // namespace enavi::worlds
