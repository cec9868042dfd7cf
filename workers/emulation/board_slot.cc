#include "workers/emulation/board_slot.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "api/fixed.h"
#include "workers/board/host_calibration.h"
#include "workers/emulation/termination_signals.h"

namespace enavi::emulation {

using api::Fixed;

double BoardSlot::HostSpeedNow(const board::HostCalibration& cal, const EmulationOptions& emulation) {
  if (!emulation.probe_host_speed) {
    notes_["emulation.speed_probe"] = "none: the calibration's speed " + Fixed(cal.relative_speed, 3) + " stands";
    return cal.relative_speed;
  }
  const board::SpeedProbe probe = emulation.probe_host_speed();
  const board::SpeedDrift d = board::DriftSinceCalibration(cal, probe.speed);
  const board::DriftText text = board::DescribeDrift(cal, probe);
  const double used = emulation.use_probed_speed ? d.host_speed : cal.relative_speed;
  notes_["emulation.speed_probe"] =
      text.drift + "; " + text.spread + "; " + Fixed(probe.wall_s, 1) + " s, " + std::to_string(probe.jobs) + " jobs" +
      (emulation.use_probed_speed ? ": host speed " + Fixed(used, 3) + " used"
                                  : ": not used (the calibration's " + Fixed(used, 3) + " is)");
  if (std::abs(d.ratio - 1) > board::kSpeedDriftWarning) {
    std::fprintf(stderr, "enavi: warning: %s; %s; `enavi calibrate` refits this host's costs\n", text.drift.c_str(),
                 emulation.use_probed_speed ? "the board is emulated at the speed now"
                                            : "the board is emulated at the calibration's speed, off by as much");
  }
  if (probe.Spread() > board::kSpeedDriftWarning) {
    std::fprintf(stderr,
                 "enavi: warning: %s: a VM whose vCPUs share physical cores with other guests; the board runs "
                 "at the speed of whichever its threads land on\n",
                 text.spread.c_str());
  }
  return used;
}

BoardSlot::BoardSlot(const board::BoardProfile& board, double dilation, const EmulationOptions& emulation) {
  // 1. This host's speed (calibration) -> the board's speed relative to it.
  const std::string path = board::CalibrationPath(emulation.calibration_file);
  const board::CalibrationCheck check = board::CheckHostCalibration(path);
  if (!check.ok()) throw std::invalid_argument("--clock emulated needs a valid host calibration: " + check.message);
  const board::HostCalibration& cal = *check.calibration;
  const double host_speed = HostSpeedNow(cal, emulation);
  speed_ = board::SpeedVsHost(board, host_speed);
  notes_["emulation.speed"] = Fixed(speed_, 4) + " of a host core per board core (board " +
                              Fixed(board.per_core_speed, 3) + " / host " + Fixed(host_speed, 3) +
                              " x the reference core; calibration " + path + ", " + cal.date + ")" +
                              (speed_ > 1.0 ? "; the board's cores are " + Fixed(100 * (speed_ - 1), 1) +
                                                  " % faster than the host's: time is dilated at least as much"
                                            : "");
  if (dilation > 0 && dilation < speed_) {
    throw std::invalid_argument("--clock emulated: board '" + board.id + "' has cores " + Fixed(speed_, 3) +
                                " x as fast as this host's, so the dilation must be at least " + Fixed(speed_, 3) +
                                " (a thread gets speed / dilation of a host core, at most one); got " +
                                Fixed(dilation, 2));
  }

  // 2. cgroups: detect, reap stale groups, admit.
  CgroupOptions cg;
  auto open = CgroupManager::Open(cg);
  if (!open.ok()) {
    throw std::invalid_argument("--clock emulated needs a writable cgroup hierarchy (run as root, cgroup v2 with "
                                "cpu/cpuset/memory delegated or v1 cpu/cpuset/memory mounted read-write): " +
                                open.error + "; the virtual clock (--clock virtual) needs none of this");
  }
  manager_ = std::move(open.manager);
  if (!open.reaped.empty()) {
    std::string list;
    for (const auto& r : open.reaped) list += (list.empty() ? "" : ", ") + r;
    notes_["emulation.reaped"] = list;
  }
  // Admission: other emulated episodes on this host hold CPUs. Auto dilation takes the smallest
  // k at which the board fits what is free, as long as a thread's quota stays above what the
  // kernel enforces; otherwise (and when admission is refused) the episode waits for them, up to
  // admission_wait_s.
  const BoardCpu cpu{board.cores, speed_};
  const auto started = std::chrono::steady_clock::now();
  const auto give_up = started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                     std::chrono::duration<double>(emulation.admission_wait_s));
  const double max_auto_dilation = speed_ * static_cast<double>(emulation.cfs_period_us) / kMinQuotaUs;
  for (;;) {
    const double host_cpus = manager_->HostCpus();
    const double reserved = manager_->ReservedCpus();
    const double free_cpus = host_cpus - cg.host_reserve_cpus - reserved;
    std::string refusal;
    dilation_ = dilation;
    if (dilation_ <= 0) {
      dilation_ = free_cpus >= 0.05 ? MinimumDilation(cpu, free_cpus) : 0.0;
      if (dilation_ <= 0 || dilation_ > max_auto_dilation) {
        refusal = "admission refused: " + Fixed(std::max(0.0, free_cpus), 2) + " host CPUs free (host " +
                  Fixed(host_cpus, 0) + " CPUs, " + Fixed(reserved, 3) + " held by running emulations, " +
                  Fixed(cg.host_reserve_cpus, 2) + " kept for the simulator): the board would need a dilation above " +
                  Fixed(max_auto_dilation, 2) + ", where a thread's quota falls below the kernel's 1 ms";
      } else {
        notes_["emulation.dilation"] = Fixed(dilation_, 2) + " (auto: smallest multiple of 0.25 at which " +
                                       std::to_string(board.cores) + " x " + Fixed(speed_, 3) + " = " +
                                       Fixed(board.cores * speed_, 3) + " host CPUs fit the " + Fixed(free_cpus, 2) +
                                       " free" + (speed_ > 1.0 ? " and is at least the speed" : "") + ")";
      }
    } else {
      notes_["emulation.dilation"] = Fixed(dilation_, 2) + " (requested)";
    }
    if (refusal.empty()) {
      QuotaOptions qo;
      qo.dilation = dilation_;
      qo.period_us = emulation.cfs_period_us;
      quota_ = ComputeBoardQuota(cpu, qo);
      EpisodeLimits limits;
      limits.cpus = emulation.cpus;
      auto created = manager_->CreateEpisode(quota_, limits);
      if (created.ok()) {
        group_ = std::move(created.group);
        break;
      }
      refusal = created.refusal;
    }
    if (std::chrono::steady_clock::now() >= give_up || PendingTerminationSignal() != 0)
      throw std::invalid_argument("--clock emulated: " + refusal +
                                  (emulation.admission_wait_s > 0
                                       ? " (waited " + Fixed(emulation.admission_wait_s, 0) + " s)"
                                       : ""));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  if (const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(); waited > 1)
    notes_["emulation.admission"] = "waited " + Fixed(waited, 1) + " s for host CPUs held by other emulated episodes";
  notes_["emulation.cgroup"] =
      std::string(manager_->layout().version == CgroupVersion::kV2 ? "v2 " : "v1 ") + group_->name() +
      ": board quota " + std::to_string(quota_.board_quota_us) + " us / " + std::to_string(quota_.period_us) +
      " us (" + Fixed(quota_.BoardCpus(), 3) + " host CPUs), per thread " + std::to_string(quota_.core_quota_us) +
      " us (" + Fixed(quota_.CoreCpus(), 3) + ")" + (emulation.cpus.empty() ? "" : ", cpuset " + emulation.cpus);
}

std::string BoardSlot::Release() {
  std::string error;
  if (group_) {
    if (CgroupStatus s = group_->Remove(); !s.ok) error = s.message;
    group_.reset();
  }
  manager_.reset();  // removes the `enavi` parent unless other episodes live in it
  return error;
}

BoardSlot::~BoardSlot() { Release(); }

}  // namespace enavi::emulation
