#pragma once
// Eigen's dense decompositions, for the matrix types fast/ uses, compiled once
// (numerics/eigen_instances_*.cpp) instead of in every translation unit of fast/
// that uses them (internal header).
//
// An explicit instantiation declaration (`extern template class`) tells the
// compiler that the members not defined inline in the class — compute(), the
// Schur, QZ and Jacobi sweeps behind it — exist in another unit, so it does
// not instantiate and optimise them again here. Measured on fast/src/model.cpp
// (EigenSolver, GeneralizedEigenSolver, PartialPivLU, HouseholderQR), gcc 12,
// the CI's sanitizer + coverage flags: 110 s → 53 s; the library's units
// repeated these instantiations in ten units. Results are unchanged: the same
// template code, compiled with the same flags, in one place.
//
// Include it in every fast/ unit that uses one of these classes (or the
// MatrixBase shorthands that build them: eigenvalues(), inverse(),
// partialPivLu(), householderQr(), colPivHouseholderQr(), ldlt(), llt()).
// A type missing here is still correct, only compiled where it is used.
#include <Eigen/Dense>

// Three groups, each instantiated by its own unit (eigen_instances_*.cpp), so
// that a 2-core build compiles them side by side: as one unit they were the
// longest compile of fast/ (120 s under the CI's sanitizer + coverage flags)
// and, listed last, left one core idle at the end of the library.
#define FDSID_EIGEN_SVD(X)                                    \
  X(Eigen::JacobiSVD<Eigen::MatrixXd>)                        \
  X(Eigen::JacobiSVD<Eigen::MatrixXcd>)                       \
  X(Eigen::BDCSVD<Eigen::MatrixXd>)

#define FDSID_EIGEN_EIGENVALUES(X)                            \
  X(Eigen::EigenSolver<Eigen::MatrixXd>)                      \
  X(Eigen::ComplexEigenSolver<Eigen::MatrixXcd>)              \
  X(Eigen::GeneralizedEigenSolver<Eigen::MatrixXd>)           \
  X(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>)           \
  X(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>)          \
  X(Eigen::RealSchur<Eigen::MatrixXd>)                        \
  X(Eigen::RealQZ<Eigen::MatrixXd>)                           \
  X(Eigen::ComplexSchur<Eigen::MatrixXcd>)

#define FDSID_EIGEN_FACTORISATIONS(X)                         \
  X(Eigen::PartialPivLU<Eigen::MatrixXd>)                     \
  X(Eigen::PartialPivLU<Eigen::MatrixXcd>)                    \
  X(Eigen::HouseholderQR<Eigen::MatrixXd>)                    \
  X(Eigen::ColPivHouseholderQR<Eigen::MatrixXd>)              \
  X(Eigen::LLT<Eigen::MatrixXd>)                              \
  X(Eigen::LDLT<Eigen::MatrixXd>)

#define FDSID_EIGEN_DECOMPOSITIONS(X) FDSID_EIGEN_SVD(X) FDSID_EIGEN_EIGENVALUES(X) FDSID_EIGEN_FACTORISATIONS(X)

#define FDSID_EIGEN_EXTERN(T) extern template class T;
FDSID_EIGEN_DECOMPOSITIONS(FDSID_EIGEN_EXTERN)
#undef FDSID_EIGEN_EXTERN
