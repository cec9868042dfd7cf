#pragma once
// The registry of navigation methods (method.h): every list a user sees reads it. Its own target,
// enavi::methods, because the built-ins it holds are built on the method interface.

#include <deque>
#include <string>
#include <string_view>
#include <vector>

#include "navstack/methods/method.h"

namespace enavi::navstack {

/// Every registered method, built-ins first, in registration order.
const std::deque<MethodInfo>& Methods();
std::vector<std::string> MethodNames();
/// The method called `name`, or null.
const MethodInfo* FindMethod(std::string_view name);
/// Adds a method. @throws std::invalid_argument for a duplicate or empty name, a missing
/// factory, or a tunable whose default lies outside its range.
void RegisterMethod(MethodInfo method);

/// Options for method `info`: configure(), then its tunables' defaults in options->params.
void ConfigureMethod(const MethodInfo& info, const MethodSetup& setup, NavStackOptions* options);

}  // namespace enavi::navstack
