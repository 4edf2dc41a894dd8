#pragma once
// The chunked (streamed) Householder QR of fast/ (internal header).
#include <Eigen/Dense>
#include <functional>

namespace fdsid::numerics {

/// fill(g0, g1, rows) writes the rows of groups g0 … g1−1 (rows_per_group each,
/// group g0 first) into `rows` ((g1 − g0)·rows_per_group × cols), every entry:
/// `rows` holds the previous chunk's Householder vectors, not zeros.
using ChunkFill = std::function<void(int g0, int g1, Eigen::Ref<Eigen::MatrixXd> rows)>;

/// The chunking of streamed_qr_r: fixed by the problem's dimensions and these
/// options only, never by the machine, so R is bit-identical whatever the
/// core count.
struct StreamedQrOptions {
  /// Rows per chunk: a chunk holds max(1, rows_per_chunk / rows_per_group)
  /// whole groups, so the work matrix (cols + rows_per_chunk) × cols stays in
  /// cache for the cols ≲ 10² of fdsid's least-squares problems.
  int rows_per_chunk = 2048;
  /// Work per block: the groups are cut into
  /// B = clamp(⌊2·rows·cols² / flops_per_block⌋, 1, max_blocks) contiguous
  /// blocks (at most one per group), each reduced independently; threads only
  /// pay off above ≈ 2^24 flops of QR (a Monte Carlo caller already runs
  /// identifications in parallel). 0 disables blocking (B = 1).
  double flops_per_block = 1 << 24;
  int max_blocks = 8;
  /// Threads over the blocks; 0: std::thread::hardware_concurrency(). Only
  /// the speed depends on it, never R.
  int threads = 0;
};

/// R factor (cols × cols, upper triangular, row signs arbitrary) of the tall
/// matrix of `groups` × rows_per_group rows produced by `fill`, which is never
/// stored whole (TSQR: Demmel, Grigori, Hoemmen & Langou 2012).
/// Method: per block, R ← R of [R; next chunk] by one Householder QR of a fixed
/// work matrix (the unused rows of a last, partial chunk are zero and leave R
/// unchanged); the B block R's are stacked in block order and reduced by one
/// more QR. The blocks run on min(B, hardware threads) threads, but which rows
/// form a block and the order of the merge depend on the dimensions only.
/// Numerical aspects: backward stable, R is the exact R of A + ΔA with
/// ‖ΔA‖_F ≲ γ̃_{rows·cols} ‖A‖_F (Higham, Accuracy and Stability, Thm 19.4);
/// O(rows·cols²) flops, O((cols + rows_per_chunk)·cols) memory per block.
/// `fill` must be safe to call from several threads at once on disjoint
/// groups when B > 1.
/// References: Demmel et al., SIAM J. Sci. Comput. 34 (2012) A206-A239.
Eigen::MatrixXd streamed_qr_r(int groups, int rows_per_group, int cols, const ChunkFill& fill,
                              const StreamedQrOptions& options = {});

}  // namespace fdsid::numerics
