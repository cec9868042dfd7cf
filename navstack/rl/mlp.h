#pragma once
// Multi-layer perceptron with tanh hidden layers and a linear output, parameters in one flat
// vector (so optimisers, checkpoints and gradient checks see a single array), forward and manual
// backward passes with Eigen.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "navstack/rl/random.h"

namespace enavi::navstack::rl {

class Mlp {
 public:
  Mlp() = default;
  /// sizes = {inputs, hidden_1, ..., outputs}, at least two entries, all >= 1. Weights start at 0.
  /// @throws std::invalid_argument otherwise.
  explicit Mlp(std::vector<int> sizes);

  int input_size() const { return sizes_.front(); }
  int output_size() const { return sizes_.back(); }
  int num_layers() const { return static_cast<int>(sizes_.size()) - 1; }
  const std::vector<int>& sizes() const { return sizes_; }

  /// Flat parameters: for each layer l, W_l (out x in, column-major) then b_l (out).
  Eigen::Index num_params() const { return params_.size(); }
  const Eigen::VectorXd& params() const { return params_; }
  Eigen::VectorXd& params() { return params_; }

  /// Views of layer l's weights and biases inside params().
  Eigen::Map<const Eigen::MatrixXd> W(int layer) const;
  Eigen::Map<Eigen::MatrixXd> W(int layer);
  Eigen::Map<const Eigen::VectorXd> b(int layer) const;
  Eigen::Map<Eigen::VectorXd> b(int layer);
  /// Offset of W_l in params(); b_l follows it.
  Eigen::Index offset(int layer) const { return offsets_[static_cast<std::size_t>(layer)]; }

  /// Orthogonal initialisation (the usual PPO choice): hidden layers with gain sqrt(2), the output
  /// layer with `output_gain`; biases zero.
  void InitOrthogonal(Rng* rng, double output_gain);

  /// Scratch for single-sample forward passes (one vector per hidden layer).
  struct Workspace {
    std::vector<Eigen::VectorXd> h;
  };
  Workspace MakeWorkspace() const;

  /// y = f(x) for one sample, no allocation. @pre x.size() == input_size(),
  /// y.size() == output_size(), ws from MakeWorkspace() of a network with the same sizes.
  void Forward(const Eigen::Ref<const Eigen::VectorXd>& x, Workspace* ws,
               Eigen::Ref<Eigen::VectorXd> y) const;

  /// Activations of a batch forward pass, kept for the backward pass.
  struct BatchCache {
    std::vector<Eigen::MatrixXd> a;  ///< a[0] = X; a[l] = tanh output of hidden layer l
  };
  /// Y = f(X), one sample per column.
  void ForwardBatch(const Eigen::Ref<const Eigen::MatrixXd>& X, BatchCache* cache,
                    Eigen::MatrixXd* Y) const;
  /// Adds dLoss/dparams to `grad` (size num_params()) given dLoss/dY of the batch in `cache`.
  void BackwardBatch(const BatchCache& cache, const Eigen::Ref<const Eigen::MatrixXd>& dY,
                     Eigen::Ref<Eigen::VectorXd> grad) const;

  /// Multiply-adds of one single-sample forward pass (sum of in x out over layers).
  std::int64_t MacsPerSample() const;
  /// tanh evaluations of one forward pass (sum of hidden widths).
  std::int64_t ActivationsPerSample() const;

 private:
  std::vector<int> sizes_{1, 1};
  std::vector<Eigen::Index> offsets_{0};
  Eigen::VectorXd params_ = Eigen::VectorXd::Zero(2);
};

}  // namespace enavi::navstack::rl
