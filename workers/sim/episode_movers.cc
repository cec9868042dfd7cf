#include "workers/sim/episode_movers.h"

#include <stdexcept>
#include <utility>

namespace enavi::sim {

std::shared_ptr<const PreparedMovers> PrepareMovers(const worlds::World& world) {
  if (world.movers.empty()) return nullptr;
  auto prepared = std::make_shared<PreparedMovers>();
  for (const worlds::Mover& m : world.movers) {
    prepared->names.push_back(m.name);
    prepared->trajectories.emplace_back(m);
    prepared->meshes.push_back(worlds::MoverMesh(m));
    prepared->shapes.push_back(std::make_shared<const StaticCollisionWorld>(prepared->meshes.back()));
  }
  return prepared;
}

EpisodeMovers::EpisodeMovers(std::shared_ptr<const PreparedMovers> movers, std::shared_ptr<const EmbreeScene> world,
                             QuadrotorSim* quad)
    : movers_(std::move(movers)), scene_(std::move(world), movers_->meshes) {
  const std::vector<Eigen::Isometry3d> X = PosesAt(0.0);
  for (std::size_t i = 0; i < X.size(); ++i) bodies_.push_back(quad->AddKinematicBody(movers_->shapes[i], X[i]));
}

std::vector<Eigen::Isometry3d> EpisodeMovers::PosesAt(double t) const {
  std::vector<Eigen::Isometry3d> X;
  X.reserve(movers_->trajectories.size());
  for (const auto& trajectory : movers_->trajectories) X.push_back(trajectory.Pose(t).Transform());
  return X;
}

void EpisodeMovers::PoseBodies(double t, QuadrotorSim* quad) const {
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    quad->SetKinematicPose(bodies_[i], movers_->trajectories[i].Pose(t).Transform());
  }
}

const MovingScene& EpisodeMovers::SceneAt(double t) {
  scene_.SetPoses(PosesAt(t));
  return scene_;
}

std::string EpisodeMovers::Touched(int body) const {
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i] == body) return "mover:" + movers_->names[i];
  }
  if (body < 0) return "static";
  throw std::logic_error("EpisodeMovers::Touched: body " + std::to_string(body) + " is no mover");
}

}  // namespace enavi::sim
