#pragma once
// Child processes for the farm: fork/exec with resource limits, captured output, its own process
// group (so a timeout kills everything it started) and death with its parent (PR_SET_PDEATHSIG),
// so a killed worker or test leaves no episode behind.

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace enavi::worker {

// An AddressSanitizer build (detected at compile time: GCC defines __SANITIZE_ADDRESS__, clang
// answers __has_feature) reserves its shadow memory, about 20 TiB of address space on x86-64, as
// a child starts, so no useful RLIMIT_AS leaves room for it: the child dies before main. There the
// limit is not applied and the worker's log says so (kAddressSpaceLimitOff); elsewhere it is.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSpaceLimitApplies = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSpaceLimitApplies = false;
#else
inline constexpr bool kAddressSpaceLimitApplies = true;
#endif
#else
inline constexpr bool kAddressSpaceLimitApplies = true;
#endif
inline constexpr const char* kAddressSpaceLimitOff =
    "the address-space limit (RLIMIT_AS) is not applied: this build uses AddressSanitizer, whose "
    "shadow memory reserves terabytes of address space";

struct SpawnOptions {
  std::vector<std::string> argv;                ///< argv[0]: a path, or a name looked up in PATH
  std::vector<std::string> env;                 ///< NAME=value added to (or replacing) environ
  std::filesystem::path cwd;                    ///< empty: inherit
  std::filesystem::path stdout_file;            ///< empty: inherit
  std::filesystem::path stderr_file;            ///< empty: inherit
  std::int64_t memory_limit_bytes = 0;          ///< RLIMIT_AS; 0: none (ignored under ASan)
  std::int64_t cpu_limit_s = 0;                 ///< RLIMIT_CPU (SIGXCPU, then SIGKILL); 0: none
  bool die_with_parent = true;                  ///< PR_SET_PDEATHSIG = SIGKILL
};

/// How a child ended.
struct ExitStatus {
  bool exited = false;  ///< true: exit code valid; false: killed by `signal`
  int code = 0;
  int signal = 0;
  bool ok() const { return exited && code == 0; }
  std::string Describe() const;  ///< "exit code 3", "killed by signal 9 (Killed)"
};

/// A running child. Move-only; destroying a still-running child kills its process group.
class ChildProcess {
 public:
  /// Forks and execs. @throws std::runtime_error when fork fails or argv[0] is not executable
  /// (checked before forking, so a typo is an error here, not a cryptic exit code later).
  static ChildProcess Spawn(const SpawnOptions& options);

  ChildProcess() = default;
  ~ChildProcess();
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  bool running() const { return pid_ > 0 && !status_; }
  /// Non-blocking: the exit status once the child has ended.
  std::optional<ExitStatus> Poll();
  /// Waits up to `timeout` (max(): forever).
  std::optional<ExitStatus> Wait(std::chrono::milliseconds timeout);
  /// Sends `signal` to the child's whole process group.
  void Signal(int signal);
  /// SIGTERM, up to `grace` to end, then SIGKILL; returns the final status.
  ExitStatus Terminate(std::chrono::milliseconds grace);

 private:
  pid_t pid_ = -1;
  std::optional<ExitStatus> status_;
};

/// Path of the running executable (/proc/self/exe resolved).
std::filesystem::path SelfExecutable();

/// Splits a command line on whitespace, honouring '...' and "..." quoting (no expansion).
/// @throws std::invalid_argument on an unterminated quote or an empty command.
std::vector<std::string> SplitCommand(const std::string& command);

}  // namespace enavi::worker
