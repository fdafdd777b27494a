// Eigen values into their protocol messages, for every place that fills a
// State or a Frame.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sim4cv.pb.h"

namespace sim4cv::wire {

inline void SetVec3(const Eigen::Vector3d& v, proto::Vec3& out) {
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
}

inline void SetQuaternion(const Eigen::Quaterniond& q, proto::Quaternion& out) {
  out.set_w(q.w());
  out.set_x(q.x());
  out.set_y(q.y());
  out.set_z(q.z());
}

}  // namespace sim4cv::wire
