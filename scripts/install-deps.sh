#!/usr/bin/env bash
# Installs everything E-Navi Farm needs to build and test, from Debian 12's packages.
# Idempotent: packages already present are left alone. Needs root (or sudo).
set -euo pipefail

packages=(
  build-essential cmake pkg-config git ca-certificates
  clang libclang-rt-14-dev lld
  libbullet-dev libeigen3-dev liboctomap-dev libembree-dev
  cyclonedds-dev cyclonedds-tools
  libompl-dev libboost-serialization-dev libboost-filesystem-dev libboost-system-dev liblbfgs-dev
  libboost-program-options-dev
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev libsqlite3-dev sqlite3
  libcpp-httplib-dev libssl-dev zlib1g-dev libpng-dev libcairo2-dev fonts-dejavu-core
  libjs-chart.js  # the dashboard's charts, embedded into enavi at build time
  libassimp-dev libsdformat-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-dev pybind11-dev python3-numpy python3-torch
  iproute2 procps util-linux nftables
  munge slurmctld slurmd slurm-client python3-jsonschema python3-yaml
  chromium chromium-driver python3-selenium libxml2-utils
  # The ROS 1 bridge (docs/ros.md): roscpp, the master, roslaunch, rosbag, message generation and
  # the message packages it speaks. Optional for the core: without them the bridge is not built.
  ros-core-dev libroscpp-dev python3-rosmaster python3-roslaunch python3-rosbag python3-rostopic python3-rosnode
  python3-gencpp python3-genmsg catkin libtopic-tools-dev libstd-msgs-dev libgeometry-msgs-dev libsensor-msgs-dev
  libnav-msgs-dev libtf2-msgs-dev libros-rosgraph-msgs-dev libtrajectory-msgs-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
echo "install-deps: installing ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
