#include "navstack/rl/mlp.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/QR>

namespace enavi::navstack::rl {

Mlp::Mlp(std::vector<int> sizes) : sizes_(std::move(sizes)) {
  if (sizes_.size() < 2) throw std::invalid_argument("Mlp: need at least input and output sizes");
  for (std::size_t i = 0; i < sizes_.size(); ++i) {
    if (sizes_[i] < 1) {
      throw std::invalid_argument("Mlp: layer size " + std::to_string(i) + " is " +
                                  std::to_string(sizes_[i]) + ", must be >= 1");
    }
  }
  offsets_.clear();
  Eigen::Index n = 0;
  for (int l = 0; l < num_layers(); ++l) {
    offsets_.push_back(n);
    n += static_cast<Eigen::Index>(sizes_[l + 1]) * (sizes_[l] + 1);
  }
  params_ = Eigen::VectorXd::Zero(n);
}

Eigen::Map<const Eigen::MatrixXd> Mlp::W(int l) const {
  return {params_.data() + offset(l), sizes_[l + 1], sizes_[l]};
}
Eigen::Map<Eigen::MatrixXd> Mlp::W(int l) {
  return {params_.data() + offset(l), sizes_[l + 1], sizes_[l]};
}
Eigen::Map<const Eigen::VectorXd> Mlp::b(int l) const {
  return {params_.data() + offset(l) + static_cast<Eigen::Index>(sizes_[l + 1]) * sizes_[l],
          sizes_[l + 1]};
}
Eigen::Map<Eigen::VectorXd> Mlp::b(int l) {
  return {params_.data() + offset(l) + static_cast<Eigen::Index>(sizes_[l + 1]) * sizes_[l],
          sizes_[l + 1]};
}

void Mlp::InitOrthogonal(Rng* rng, double output_gain) {
  for (int l = 0; l < num_layers(); ++l) {
    const int out = sizes_[l + 1], in = sizes_[l];
    const double gain = l + 1 == num_layers() ? output_gain : std::sqrt(2.0);
    // Orthonormal columns of a Gaussian matrix (QR with R's diagonal made positive), transposed
    // when the layer is wider than tall.
    const int rows = std::max(out, in), cols = std::min(out, in);
    Eigen::MatrixXd g(rows, cols);
    for (int j = 0; j < cols; ++j) {
      for (int i = 0; i < rows; ++i) g(i, j) = rng->Normal();
    }
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
    Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(rows, cols);
    for (int j = 0; j < cols; ++j) {
      if (qr.matrixQR()(j, j) < 0.0) q.col(j) *= -1.0;
    }
    if (out >= in) {
      W(l) = gain * q;
    } else {
      W(l) = gain * q.transpose();
    }
    b(l).setZero();
  }
}

Mlp::Workspace Mlp::MakeWorkspace() const {
  Workspace ws;
  for (int l = 0; l + 1 < num_layers(); ++l) ws.h.emplace_back(sizes_[l + 1]);
  return ws;
}

void Mlp::Forward(const Eigen::Ref<const Eigen::VectorXd>& x, Workspace* ws,
                  Eigen::Ref<Eigen::VectorXd> y) const {
  const int last = num_layers() - 1;
  if (last == 0) {
    y.noalias() = W(0) * x;
    y += b(0);
    return;
  }
  for (int l = 0; l < last; ++l) {
    Eigen::VectorXd& h = ws->h[static_cast<std::size_t>(l)];
    if (l == 0) {
      h.noalias() = W(0) * x;
    } else {
      h.noalias() = W(l) * ws->h[static_cast<std::size_t>(l - 1)];
    }
    h = (h + b(l)).array().tanh().matrix();
  }
  y.noalias() = W(last) * ws->h[static_cast<std::size_t>(last - 1)];
  y += b(last);
}

void Mlp::ForwardBatch(const Eigen::Ref<const Eigen::MatrixXd>& X, BatchCache* cache,
                       Eigen::MatrixXd* Y) const {
  const int last = num_layers() - 1;
  cache->a.resize(static_cast<std::size_t>(num_layers()));
  cache->a[0] = X;
  for (int l = 0; l < last; ++l) {
    Eigen::MatrixXd z = W(l) * cache->a[static_cast<std::size_t>(l)];
    z.colwise() += b(l);
    cache->a[static_cast<std::size_t>(l + 1)] = z.array().tanh().matrix();
  }
  *Y = W(last) * cache->a[static_cast<std::size_t>(last)];
  Y->colwise() += b(last);
}

void Mlp::BackwardBatch(const BatchCache& cache, const Eigen::Ref<const Eigen::MatrixXd>& dY,
                        Eigen::Ref<Eigen::VectorXd> grad) const {
  // dZ is dLoss/d(pre-activation) of the current layer; walk from the output back to the input.
  Eigen::MatrixXd dz = dY;
  for (int l = num_layers() - 1; l >= 0; --l) {
    const Eigen::MatrixXd& a_in = cache.a[static_cast<std::size_t>(l)];
    const int out = sizes_[l + 1], in = sizes_[l];
    Eigen::Map<Eigen::MatrixXd> gW(grad.data() + offset(l), out, in);
    Eigen::Map<Eigen::VectorXd> gb(grad.data() + offset(l) + static_cast<Eigen::Index>(out) * in,
                                   out);
    gW.noalias() += dz * a_in.transpose();
    gb += dz.rowwise().sum();
    if (l > 0) {
      // Through W_l, then through tanh of layer l-1: d tanh = 1 - tanh^2.
      Eigen::MatrixXd da = W(l).transpose() * dz;
      dz = (da.array() * (1.0 - a_in.array().square())).matrix();
    }
  }
}

std::int64_t Mlp::MacsPerSample() const {
  std::int64_t n = 0;
  for (int l = 0; l < num_layers(); ++l) n += static_cast<std::int64_t>(sizes_[l]) * sizes_[l + 1];
  return n;
}

std::int64_t Mlp::ActivationsPerSample() const {
  std::int64_t n = 0;
  for (int l = 1; l + 1 < static_cast<int>(sizes_.size()); ++l) n += sizes_[l];
  return n;
}

}  // namespace enavi::navstack::rl
