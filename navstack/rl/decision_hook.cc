#include "navstack/rl/decision_hook.h"

namespace enavi::navstack::rl {
namespace {

thread_local DecisionHook* current_hook = nullptr;

}  // namespace

DecisionHook* CurrentDecisionHook() { return current_hook; }

ScopedDecisionHook::ScopedDecisionHook(DecisionHook* hook) : previous_(current_hook) { current_hook = hook; }

ScopedDecisionHook::~ScopedDecisionHook() { current_hook = previous_; }

}  // namespace enavi::navstack::rl
