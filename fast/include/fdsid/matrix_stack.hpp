#pragma once
/// F matrices of one shape in one contiguous block: the per-frequency storage
/// of FrfData (issue 16). A std::vector of F small Eigen matrices spent two
/// heap blocks' bookkeeping per frequency on a 1 × 1 entry (an F = 10⁶ FRF file
/// held 168 MiB where its numbers are 40 MB) and a malloc/free per frequency
/// and per Monte Carlo run; here matrix k is entries [k·rows·cols, (k+1)·rows·cols)
/// of one array, column-major like Eigen's, viewed through an Eigen::Map.
#include <complex>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fdsid/error.hpp"

namespace fdsid {

template <class Scalar>
class MatrixStack {
 public:
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using View = Eigen::Map<Matrix>;
  using ConstView = Eigen::Map<const Matrix>;

  MatrixStack() = default;
  /// `count` matrices rows × cols, every entry zero.
  MatrixStack(Eigen::Index count, Eigen::Index rows, Eigen::Index cols) { resize(count, rows, cols); }
  /// The matrices of `matrices`, which must share one shape (Error(Input)
  /// naming the first that does not).
  explicit MatrixStack(const std::vector<Matrix>& matrices) {
    if (!matrices.empty()) reserve(static_cast<Eigen::Index>(matrices.size()), matrices[0].rows(), matrices[0].cols());
    for (const Matrix& x : matrices) push_back(x);
  }

  Eigen::Index size() const { return count_; }
  bool empty() const { return count_ == 0; }
  Eigen::Index rows() const { return rows_; }
  Eigen::Index cols() const { return cols_; }

  View operator[](Eigen::Index k) { return View(data_.data() + k * rows_ * cols_, rows_, cols_); }
  ConstView operator[](Eigen::Index k) const { return ConstView(data_.data() + k * rows_ * cols_, rows_, cols_); }
  /// Entry (i, j) of matrix k: for loops over all frequencies, without a Map each.
  Scalar& operator()(Eigen::Index k, Eigen::Index i, Eigen::Index j) { return data_[(k * cols_ + j) * rows_ + i]; }
  Scalar operator()(Eigen::Index k, Eigen::Index i, Eigen::Index j) const { return data_[(k * cols_ + j) * rows_ + i]; }
  const Scalar* data() const { return data_.data(); }

  /// `count` matrices rows × cols, every entry zero (the old ones dropped).
  void resize(Eigen::Index count, Eigen::Index rows, Eigen::Index cols) {
    rows_ = rows;
    cols_ = cols;
    count_ = count;
    data_.assign(static_cast<std::size_t>(count * rows * cols), Scalar(0));
  }
  /// Room for `count` matrices rows × cols (a hint: push_back still grows).
  void reserve(Eigen::Index count, Eigen::Index rows, Eigen::Index cols) {
    data_.reserve(static_cast<std::size_t>(count * rows * cols));
  }
  void clear() {
    count_ = 0;
    data_.clear();
  }
  /// Appends x; the first matrix fixes the shape, a later one of another shape
  /// is refused (Error(Input) naming it: the stack would be misread). x must
  /// not view this stack (growing it may move the block).
  template <class Derived>
  void push_back(const Eigen::MatrixBase<Derived>& x) {
    if (count_ == 0) {
      rows_ = x.rows();
      cols_ = x.cols();
    } else if (x.rows() != rows_ || x.cols() != cols_) {
      throw Error(ErrorKind::Input, "frequency " + std::to_string(count_ + 1),
                  "inconsistent shapes: " + std::to_string(x.rows()) + " x " + std::to_string(x.cols()) +
                      " after " + std::to_string(rows_) + " x " + std::to_string(cols_));
    }
    const std::size_t at = data_.size();
    data_.resize(at + static_cast<std::size_t>(rows_ * cols_));
    View(data_.data() + at, rows_, cols_) = x;
    ++count_;
  }
  /// Every entry of every matrix, as one column (for whole-stack checks).
  Eigen::Map<const Eigen::Matrix<Scalar, Eigen::Dynamic, 1>> entries() const {
    return {data_.data(), static_cast<Eigen::Index>(data_.size())};
  }

 private:
  Eigen::Index rows_ = 0, cols_ = 0, count_ = 0;
  std::vector<Scalar> data_;
};

using ComplexMatrixStack = MatrixStack<std::complex<double>>;
using RealMatrixStack = MatrixStack<double>;

}  // namespace fdsid
