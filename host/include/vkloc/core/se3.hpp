// vkloc: Lie groups SO(3) and SE(3) for pose optimisation.
//
// Tangent order, used everywhere in vkloc (host code and shaders):
//   xi = [rho; phi] in R^6, rho = translational part (metres), phi = rotation vector (radians).
//   hat(xi) = [hat(phi) rho; 0 0], exp(xi) = [expSO3(phi)  V(phi) rho; 0 1] with V the left
//   Jacobian of SO(3).
//
// Perturbation convention of the trackers: a pose T_a_b is updated by LEFT multiplication,
//   T_a_b <- exp(delta) * T_a_b,
// so delta is expressed in frame a (for T_camera_ref: in the camera frame). A point p_b maps to
// p_a = T_a_b p_b and d(exp(delta) p_a)/d(delta) at delta = 0 is [I | -hat(p_a)] (pointJacobian).
#pragma once

#include <Eigen/Core>

#include "vkloc/core/pose.hpp"

namespace vkloc {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Skew-symmetric matrix: hat(v) w = v x w.
Eigen::Matrix3d hat(const Eigen::Vector3d& v);

/// Inverse of hat: the vector of a skew-symmetric matrix (uses the antisymmetric part of W).
Eigen::Vector3d vee(const Eigen::Matrix3d& W);

/// 4x4 matrix of the twist xi = [rho; phi]: [hat(phi) rho; 0 0].
Eigen::Matrix4d hatSE3(const Vector6d& xi);

/// Inverse of hatSE3 (reads the antisymmetric part of the rotation block).
Vector6d veeSE3(const Eigen::Matrix4d& X);

/// Rotation matrix of the rotation vector phi (radians), Rodrigues' formula; Taylor series for
/// |phi| < 1e-2 rad, so exact to double precision near identity.
Eigen::Matrix3d expSO3(const Eigen::Vector3d& phi);

/// Rotation vector of R with |phi| in [0, pi]. Goes through a unit quaternion (Shepperd's
/// method), so it stays accurate near identity and near pi. R must be a rotation matrix.
Eigen::Vector3d logSO3(const Eigen::Matrix3d& R);

/// Angle of the rotation R in degrees, [0, 180] (|logSO3(R)|). R must be a rotation matrix.
double rotationAngleDeg(const Eigen::Matrix3d& R);

/// Left Jacobian of SO(3): expSO3(phi + d) ~= expSO3(leftJacobianSO3(phi) d) expSO3(phi) for
/// small d. Also the V matrix of expSE3.
Eigen::Matrix3d leftJacobianSO3(const Eigen::Vector3d& phi);

/// Inverse of leftJacobianSO3 (closed form; valid for |phi| < 2 pi).
Eigen::Matrix3d leftJacobianInverseSO3(const Eigen::Vector3d& phi);

/// Right Jacobian: expSO3(phi + d) ~= expSO3(phi) expSO3(rightJacobianSO3(phi) d). Equals
/// leftJacobianSO3(-phi).
Eigen::Matrix3d rightJacobianSO3(const Eigen::Vector3d& phi);

/// exp of the twist xi = [rho; phi] (metres, radians).
Pose expSE3(const Vector6d& xi);

/// log of a rigid transform: xi = [rho; phi] with |phi| in [0, pi]; expSE3(logSE3(T)) == T.
Vector6d logSE3(const Pose& T);

/// Adjoint of T for the [rho; phi] order: [R  hat(t) R; 0  R], so that
/// expSE3(adjointSE3(T) xi) == T expSE3(xi) T^-1.
Matrix6d adjointSE3(const Pose& T);

/// Jacobian of exp(delta) * p with respect to delta at delta = 0, for a point p (metres) in the
/// frame delta is expressed in: [I | -hat(p)] (3x6, columns in [rho; phi] order).
Eigen::Matrix<double, 3, 6> pointJacobian(const Eigen::Vector3d& p);

/// Left update of the convention above: expSE3(delta) * T.
Pose applyLeftIncrement(const Pose& T, const Vector6d& delta);

}  // namespace vkloc
