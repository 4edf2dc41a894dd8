#include "numerics/qr.hpp"
#include "numerics/eigen_instances.hpp"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace fdsid::numerics {

namespace {

Eigen::MatrixXd qr_range(int g0, int g1, int rows_per_group, int cols, const ChunkFill& fill, int rows_per_chunk) {
  const int chunk = std::max(1, rows_per_chunk / rows_per_group);
  Eigen::MatrixXd work = Eigen::MatrixXd::Zero(cols + chunk * rows_per_group, cols);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(work.rows(), work.cols());
  for (int a = g0; a < g1; a += chunk) {
    const int b = std::min(g1, a + chunk);
    if (b - a < chunk) work.bottomRows((chunk - (b - a)) * rows_per_group).setZero();
    fill(a, b, work.middleRows(cols, (b - a) * rows_per_group));
    qr.compute(work);
    work.topRows(cols) = qr.matrixQR().topRows(cols).triangularView<Eigen::Upper>();
  }
  return work.topRows(cols);
}

}  // namespace

Eigen::MatrixXd streamed_qr_r(int groups, int rows_per_group, int cols, const ChunkFill& fill,
                              const StreamedQrOptions& o) {
  const double flops = 2.0 * groups * rows_per_group * double(cols) * cols;
  int blocks = 1;
  if (o.flops_per_block > 0) blocks = static_cast<int>(std::min<double>(std::max(1, o.max_blocks), flops / o.flops_per_block));
  blocks = std::max(1, std::min(blocks, groups));
  if (blocks == 1) return qr_range(0, groups, rows_per_group, cols, fill, o.rows_per_chunk);
  std::vector<Eigen::MatrixXd> parts(blocks);
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int t; (t = next++) < blocks;) {
      const int a = static_cast<int>(static_cast<long long>(groups) * t / blocks);
      const int b = static_cast<int>(static_cast<long long>(groups) * (t + 1) / blocks);
      parts[t] = qr_range(a, b, rows_per_group, cols, fill, o.rows_per_chunk);
    }
  };
  const int available = o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency());
  const int threads = std::max(1, std::min(blocks, available));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
  Eigen::MatrixXd stacked(blocks * cols, cols);
  for (int t = 0; t < blocks; ++t) stacked.middleRows(t * cols, cols) = parts[t];
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked);
  return qr.matrixQR().topRows(cols).triangularView<Eigen::Upper>();
}

}  // namespace fdsid::numerics
