#pragma once
// Argument checks of the navstack's options and inputs, each message written once: a bad value
// throws with its owner, field, value and what was expected (docs/design.md, "Reliability
// rules").

namespace enavi::navstack {

/// The checks of one owner (an options struct, a computation):
///   constexpr ArgumentCheck kCheck("PerceptionOptions");
///   kCheck.Range(stride >= 1 && stride <= 64, "stride", stride, "[1, 64]");
class ArgumentCheck {
 public:
  explicit constexpr ArgumentCheck(const char* owner) : owner_(owner) {}

  /// Throws std::invalid_argument("<owner>.<field>: <value> is out of range <range>") unless ok.
  void Range(bool ok, const char* field, double value, const char* range) const;
  /// Throws std::domain_error("<owner>: <name> = <value> must be finite and >= 0") unless the
  /// value is finite and >= 0 (NaN fails).
  void NonNegative(double value, const char* name) const;

 private:
  const char* owner_;
};

}  // namespace enavi::navstack
