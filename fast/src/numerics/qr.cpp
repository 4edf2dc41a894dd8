#include "numerics/qr.hpp"
#include "numerics/eigen_instances.hpp"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace fdsid::numerics {

namespace {

// The work matrix of one block, (cols + chunk rows) × cols. A thread keeps
// its last buffer up to kKeepBytes (1 MiB for Algorithm 1 at r = 40, SISO)
// and reuses it on the next call: a fresh buffer of that size per call was
// returned to the system on free and faulted in again (perf: a third of
// identify_frf_fixed at F = 999, r = 40 in the kernel's page-fault handler).
// Larger buffers are freed when the block ends. The contents never carry
// over: the R rows start at zero and every chunk row is written by fill or
// zeroed before it is used.
constexpr std::size_t kKeepBytes = std::size_t(16) << 20;
constexpr Eigen::Index kPanel = 16;

double* work_buffer(std::vector<double>& local, std::size_t size) {
  thread_local std::vector<double> kept;
  std::vector<double>& buf = size * sizeof(double) <= kKeepBytes ? kept : local;
  if (buf.size() < size) buf.resize(size);
  return buf.data();
}

Eigen::MatrixXd qr_range(int g0, int g1, int rows_per_group, int cols, const ChunkFill& fill, int rows_per_chunk) {
  // A block of fewer groups than one chunk gets a work matrix of its own size
  // (at F = 5000, r = 40: seven blocks of 714 groups, each factored in a
  // 2128 × 80 work matrix where 1508 × 80 hold it).
  const int chunk = std::max(1, std::min(rows_per_chunk / rows_per_group, g1 - g0));
  const Eigen::Index rows = cols + static_cast<Eigen::Index>(chunk) * rows_per_group;
  std::vector<double> local;
  Eigen::Map<Eigen::MatrixXd> work(work_buffer(local, static_cast<std::size_t>(rows) * cols), rows, cols);
  work.topRows(cols).setZero();
  Eigen::VectorXd hcoeffs(cols), temp(cols);
  for (int a = g0; a < g1; a += chunk) {
    const int b = std::min(g1, a + chunk);
    if (b - a < chunk) work.bottomRows((chunk - (b - a)) * rows_per_group).setZero();
    fill(a, b, work.middleRows(cols, (b - a) * rows_per_group));
    // In place: the Householder vectors overwrite the chunk rows (the next
    // fill writes them again) and the strictly lower part of R, cleared here.
    // Eigen's blocked Householder QR (what HouseholderQR::compute runs) with
    // panels of kPanel columns instead of its 48: the panels are factored by
    // rank-one updates, the rest by blocked products, and on these tall
    // (2048 + cols) × cols matrices, cols ≲ 10², narrower panels move work
    // to the products (2128 × 80, SSE2: 1.94 ms against 2.15 ms at 48).
    Eigen::internal::householder_qr_inplace_blocked<Eigen::Map<Eigen::MatrixXd>, Eigen::VectorXd>::run(
        work, hcoeffs, kPanel, temp.data());
    work.topRows(cols).triangularView<Eigen::StrictlyLower>().setZero();
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
