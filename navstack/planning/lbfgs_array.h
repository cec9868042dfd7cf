#pragma once
// Private to enavi::planning: owner of an lbfgs_malloc'd array (liblbfgs may use SSE and needs
// its own alignment). Include only from .cc files (lbfgs.h is a private dependency).

#include <lbfgs.h>

namespace enavi::navstack {

struct LbfgsArray {
  explicit LbfgsArray(int n) : data(lbfgs_malloc(n)) {}
  ~LbfgsArray() { lbfgs_free(data); }
  LbfgsArray(const LbfgsArray&) = delete;
  LbfgsArray& operator=(const LbfgsArray&) = delete;
  lbfgsfloatval_t* data;
};

}  // namespace enavi::navstack
