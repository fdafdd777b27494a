#include "server/sim/vehicles/trajectory.h"

#include <bit>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "server/common/check.h"

namespace sim4cv::vehicles {
namespace {

// Raw IEEE-754 doubles and fixed-width integers copied as bytes: exact round
// trips, and on the little-endian hosts we build for, the documented layout.
static_assert(std::endian::native == std::endian::little, "trajectory files are little-endian");
static_assert(sizeof(double) == 8);

constexpr char kMagic[8] = {'S', '4', 'C', 'V', 'T', 'R', 'J', '\0'};
constexpr uint32_t kVersion = 1;
constexpr uint32_t kRecordSize = 144;  // bytes per sample, see docs/vehicles.md
constexpr uint32_t kFlagReverse = 1u;

class Writer {
 public:
  template <typename T>
  void Put(const T& value) {
    const auto* bytes = reinterpret_cast<const char*>(&value);
    data_.append(bytes, sizeof(T));
  }
  void Put(const Eigen::Vector3d& v) { Put(v.x()), Put(v.y()), Put(v.z()); }
  const std::string& data() const { return data_; }

 private:
  std::string data_;
};

class Reader {
 public:
  explicit Reader(std::istream& in) : data_(std::istreambuf_iterator<char>(in), {}) {}
  template <typename T>
  T Get() {
    SIM4CV_THROW_UNLESS(offset_ + sizeof(T) <= data_.size(),
                        "trajectory truncated at byte " << offset_ << " of " << data_.size());
    T value;
    std::memcpy(&value, data_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  Eigen::Vector3d GetVector() {
    const double x = Get<double>(), y = Get<double>(), z = Get<double>();
    return {x, y, z};
  }
  std::size_t remaining() const { return data_.size() - offset_; }

 private:
  std::vector<char> data_;
  std::size_t offset_ = 0;
};

}  // namespace

void WriteTrajectory(const Trajectory& trajectory, std::ostream& out) {
  Writer w;
  w.Put(kMagic);
  w.Put(kVersion);
  w.Put(kRecordSize);
  w.Put(trajectory.dt);
  w.Put(static_cast<uint64_t>(trajectory.samples.size()));
  for (const TrajectorySample& s : trajectory.samples) {
    w.Put(s.step);
    w.Put(s.state.position);
    w.Put(s.state.orientation.w()), w.Put(s.state.orientation.x());
    w.Put(s.state.orientation.y()), w.Put(s.state.orientation.z());
    w.Put(s.state.linear_velocity);
    w.Put(s.state.angular_velocity);
    w.Put(s.controls.steering), w.Put(s.controls.throttle), w.Put(s.controls.brake);
    w.Put(s.controls.reverse ? kFlagReverse : 0u);
    w.Put(uint32_t{0});  // reserved
  }
  out.write(w.data().data(), static_cast<std::streamsize>(w.data().size()));
  SIM4CV_THROW_UNLESS(out.good(), "cannot write the trajectory");
}

Trajectory ReadTrajectory(std::istream& in) {
  Reader r(in);
  char magic[sizeof(kMagic)];
  for (char& c : magic) c = r.Get<char>();
  SIM4CV_THROW_UNLESS(std::memcmp(magic, kMagic, sizeof(kMagic)) == 0, "not a trajectory file (bad magic)");
  const auto version = r.Get<uint32_t>();
  SIM4CV_THROW_UNLESS(version == kVersion,
                      "trajectory version " << version << " is not supported (only " << kVersion << ")");
  const auto record_size = r.Get<uint32_t>();
  SIM4CV_THROW_UNLESS(record_size == kRecordSize,
                      "trajectory record size " << record_size << " is not " << kRecordSize);
  Trajectory trajectory;
  trajectory.dt = r.Get<double>();
  const auto count = r.Get<uint64_t>();
  SIM4CV_THROW_UNLESS(count <= r.remaining() / kRecordSize && r.remaining() == count * kRecordSize,
                      "trajectory of " << count << " samples has " << r.remaining() << " bytes of data, expected "
                                       << count * kRecordSize);
  trajectory.samples.resize(count);
  for (TrajectorySample& s : trajectory.samples) {
    s.step = r.Get<uint64_t>();
    s.state.position = r.GetVector();
    const double w = r.Get<double>(), x = r.Get<double>(), y = r.Get<double>(), z = r.Get<double>();
    s.state.orientation = Eigen::Quaterniond(w, x, y, z);
    s.state.linear_velocity = r.GetVector();
    s.state.angular_velocity = r.GetVector();
    s.controls.steering = r.Get<double>();
    s.controls.throttle = r.Get<double>();
    s.controls.brake = r.Get<double>();
    s.controls.reverse = (r.Get<uint32_t>() & kFlagReverse) != 0;
    r.Get<uint32_t>();  // reserved
  }
  return trajectory;
}

void SaveTrajectory(const Trajectory& trajectory, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  SIM4CV_THROW_UNLESS(out.is_open(), "cannot open trajectory file '" << path << "' for writing");
  WriteTrajectory(trajectory, out);
}

Trajectory LoadTrajectory(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  SIM4CV_THROW_UNLESS(in.is_open(), "cannot open trajectory file '" << path << "'");
  return ReadTrajectory(in);
}

TrajectoryRecorder::TrajectoryRecorder(double dt) { trajectory_.dt = dt; }

void TrajectoryRecorder::Record(const VehicleState& state, const CarControls& controls) {
  trajectory_.samples.push_back({trajectory_.samples.size(), state, controls});
}

const Trajectory& TrajectoryPlayer::CheckNotEmpty(const Trajectory& trajectory) {
  SIM4CV_THROW_UNLESS(!trajectory.samples.empty(), "cannot replay an empty trajectory");
  return trajectory;
}

TrajectoryPlayer::TrajectoryPlayer(btDiscreteDynamicsWorld& world, Trajectory trajectory,
                                   const Eigen::Vector3d& half_extents)
    : trajectory_(std::move(trajectory)),
      box_(ToBullet(half_extents)),
      body_(world, box_, 0.0, ToBullet(CheckNotEmpty(trajectory_).samples.front().state.pose()),
            btCollisionObject::CF_KINEMATIC_OBJECT) {}

bool TrajectoryPlayer::Advance() {
  if (finished()) return false;
  ++index_;
  PlaceBody();
  return true;
}

void TrajectoryPlayer::PlaceBody() {
  // Bullet reads a kinematic body's pose from its motion state at the start
  // of the step (and derives its velocity from the move); setting the body's
  // transform too lets queries made before the step see the new pose.
  const btTransform pose = ToBullet(State().pose());
  body_.body().getMotionState()->setWorldTransform(pose);
  body_.body().setWorldTransform(pose);
}

}  // namespace sim4cv::vehicles
