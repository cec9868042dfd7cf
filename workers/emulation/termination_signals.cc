#include "workers/emulation/termination_signals.h"

#include <signal.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <mutex>

namespace enavi::emulation {
namespace {

std::atomic<int> g_signal{0};
std::mutex g_mutex;
int g_users = 0;
struct sigaction g_old_int{}, g_old_term{};
bool g_installed_int = false, g_installed_term = false;

extern "C" void OnTerminationSignal(int sig) { g_signal.store(sig); }

bool InstallIfDefault(int sig, struct sigaction* old) {
  struct sigaction current{};
  if (sigaction(sig, nullptr, &current) != 0 || current.sa_handler != SIG_DFL) return false;
  struct sigaction sa{};
  sa.sa_handler = OnTerminationSignal;
  sigemptyset(&sa.sa_mask);
  return sigaction(sig, &sa, old) == 0;
}

}  // namespace

int PendingTerminationSignal() { return g_signal.load(); }

ScopedTerminationSignals::ScopedTerminationSignals() {
  std::lock_guard l(g_mutex);
  if (g_users++ > 0) return;
  g_signal.store(0);
  g_installed_int = InstallIfDefault(SIGINT, &g_old_int);
  g_installed_term = InstallIfDefault(SIGTERM, &g_old_term);
}

ScopedTerminationSignals::~ScopedTerminationSignals() {
  int sig = 0;
  {
    std::lock_guard l(g_mutex);
    if (--g_users > 0) return;
    if (g_installed_int) sigaction(SIGINT, &g_old_int, nullptr);
    if (g_installed_term) sigaction(SIGTERM, &g_old_term, nullptr);
    g_installed_int = g_installed_term = false;
    sig = g_signal.exchange(0);
  }
  if (sig != 0) {
    // The episode was interrupted: now that nothing is left behind, die as the signal asked.
    std::fprintf(stderr, "enavi: %s: the episode's processes stopped and its cgroups removed\n", strsignal(sig));
    signal(sig, SIG_DFL);
    raise(sig);
  }
}

}  // namespace enavi::emulation
