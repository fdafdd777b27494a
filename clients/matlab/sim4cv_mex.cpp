// sim4cv_mex: the Octave/MATLAB gateway to sim4cv::Client (clients/matlab/README.md).
//
//   h = sim4cv_mex('connect', 'shm:///sim4cv', 'my-tracker');
//   sim4cv_mex('subscribe', h, 'uav', {'rgb','boxes'}, 'lockstep');
//   f = sim4cv_mex('frame', h, 'step');          % f.rgb: 180x320x3 uint8
//   sim4cv_mex('close', h);
//
// Handles are small integers into a registry of open clients, never reused.
// Every failure is an Octave/MATLAB error with an identifier:
// sim4cv:badHandle, sim4cv:badArgument, sim4cv:server (the daemon refused;
// the message starts with the ErrorCode name), sim4cv:connection. Clients
// are closed when the MEX file is cleared.
#include <time.h>

#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "mex.h"
#include "mex_convert.h"
#include "protocol/channels.h"
#include "sim4cv/client.h"
#include "sim4cv/shm_client.h"

namespace {

using sim4cv::Client;
namespace proto = sim4cv::proto;
namespace channels = sim4cv::channels;
using Ms = Client::Duration;

struct BadHandle : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct BadArgument : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct Session {
  Client client;
  std::string lockstep_camera;  // the camera of a lockstep subscription, "" if none
};

std::map<int, std::unique_ptr<Session>>& Sessions() {
  static auto* sessions = new std::map<int, std::unique_ptr<Session>>();  // outlives static destruction order
  return *sessions;
}
int g_next_handle = 1;

// UDP has no goodbye: a lockstep subscription would hold the simulation
// until the registration lapses (--udp-expiry-ms); an on-request one in its
// place releases it at once and is sent nothing.
void CloseSession(Session& session) {
  if (session.client.udp() && !session.lockstep_camera.empty()) {
    try {
      session.client.Subscribe(session.lockstep_camera, {proto::CHANNEL_RGB}, proto::DELIVERY_ON_REQUEST, false,
                               Ms(500));
    } catch (const std::exception&) {
      // the daemon is gone or refused: nothing is held then
    }
  }
  session.client.Close();
}

void CloseAll() {
  for (auto& [handle, session] : Sessions()) CloseSession(*session);
  Sessions().clear();
}

// The arguments of one command (after the command string), with checks that
// name the command and its usage.
class Call {
 public:
  Call(std::string command, const char* usage, int nrhs, const mxArray** prhs, int nlhs, mxArray** plhs)
      : command_(std::move(command)), usage_(usage), nrhs_(nrhs), prhs_(prhs), nlhs_(nlhs), plhs_(plhs) {}

  [[noreturn]] void Fail(const std::string& why) const {
    throw BadArgument(command_ + ": " + why + "; usage: " + usage_);
  }
  void Count(int min, int max) const {
    if (nrhs_ < min || nrhs_ > max) {
      Fail("expects " + (min == max ? std::to_string(min) : std::to_string(min) + " to " + std::to_string(max)) +
           " arguments after the command, got " + std::to_string(nrhs_));
    }
    if (nlhs_ > 1) Fail("returns at most one value");
  }
  bool Has(int i) const { return i < nrhs_; }
  double Number(int i, const char* what) const {
    const mxArray* a = prhs_[i];
    if (!(mxIsNumeric(a) || mxIsLogical(a)) || mxIsComplex(a) || mxGetNumberOfElements(a) != 1) {
      Fail(std::string(what) + " must be a real number");
    }
    const double v = mxGetScalar(a);
    if (!std::isfinite(v)) Fail(std::string(what) + " must be finite");
    return v;
  }
  double Number(int i, const char* what, double fallback) const { return Has(i) ? Number(i, what) : fallback; }
  uint32_t Id(int i, const char* what) const {
    const double v = Number(i, what);
    if (v < 0 || v > 4294967295.0 || v != std::floor(v)) Fail(std::string(what) + " must be a non-negative integer");
    return static_cast<uint32_t>(v);
  }
  std::string String(int i, const char* what) const { return StringOf(prhs_[i], what); }
  std::string StringOf(const mxArray* a, const char* what) const {
    if (!a || !mxIsChar(a) || mxGetM(a) > 1) Fail(std::string(what) + " must be a character string");
    char* text = mxArrayToString(a);
    std::string out = text ? text : "";
    mxFree(text);
    return out;
  }
  std::vector<std::string> StringList(int i, const char* what) const {
    const mxArray* a = prhs_[i];
    if (mxIsChar(a)) return {String(i, what)};
    if (!mxIsCell(a)) Fail(std::string(what) + " must be a cell array of strings");
    std::vector<std::string> out;
    for (std::size_t k = 0; k < mxGetNumberOfElements(a); ++k) {
      const mxArray* cell = mxGetCell(a, static_cast<mwIndex>(k));
      if (!cell) Fail(std::string(what) + " must be a cell array of strings");
      out.push_back(StringOf(cell, what));
    }
    return out;
  }
  Session& Handle() const {
    const mxArray* a = nrhs_ > 0 ? prhs_[0] : nullptr;
    const double v = a && mxIsDouble(a) && !mxIsComplex(a) && mxGetNumberOfElements(a) == 1 ? mxGetScalar(a) : NAN;
    const auto found = std::isfinite(v) && v == std::floor(v) ? Sessions().find(static_cast<int>(v)) : Sessions().end();
    if (found == Sessions().end()) {
      const std::string which = std::isfinite(v) ? "handle " + std::to_string(static_cast<long long>(v)) : "the handle";
      throw BadHandle(
          command_ + ": " + which +
          " is not an open sim4cv connection (closed, or never opened); use the number sim4cv_connect returned");
    }
    return *found->second;
  }
  const mxArray* Arg(int i) const { return prhs_[i]; }
  void Return(mxArray* value) const { plhs_[0] = value; }

 private:
  std::string command_;
  const char* usage_;
  int nrhs_;
  const mxArray** prhs_;
  int nlhs_;
  mxArray** plhs_;
};

// A pixel channel of the table (protocol/channels.h) or boxes.
proto::Channel ChannelOf(const Call& call, const std::string& name) {
  if (name == "boxes") return proto::CHANNEL_BOXES;
  const channels::ChannelInfo* info = channels::FindByName(name);
  if (info == nullptr) call.Fail("unknown channel '" + name + "' (" + channels::Names(channels::kAllPixels) + ",boxes)");
  return info->id;
}

proto::Delivery DeliveryOf(const Call& call, const std::string& name) {
  if (name == "lockstep") return proto::DELIVERY_LOCKSTEP;
  if (name == "newest") return proto::DELIVERY_NEWEST;
  if (name == "on_request") return proto::DELIVERY_ON_REQUEST;
  call.Fail("unknown delivery '" + name + "' (lockstep, newest, on_request)");
}

proto::EntityKind KindOf(const Call& call, const std::string& name) {
  if (name == "car") return proto::ENTITY_KIND_CAR;
  if (name == "uav") return proto::ENTITY_KIND_UAV;
  if (name == "pedestrian") return proto::ENTITY_KIND_PEDESTRIAN;
  call.Fail("unknown entity kind '" + name + "' (car, uav, pedestrian)");
}

sim4cv::CameraSetup CameraOf(const Call& call, const mxArray* s) {
  if (!mxIsStruct(s) || mxGetNumberOfElements(s) != 1) call.Fail("the camera must be a 1x1 struct");
  using Setup = sim4cv::CameraSetup;
  static const std::map<std::string, double Setup::*> kNumbers = {{"fov_y_deg", &Setup::fov_y_deg},
                                                                  {"pitch_down_deg", &Setup::pitch_down_deg},
                                                                  {"yaw_deg", &Setup::yaw_deg},
                                                                  {"x", &Setup::x},
                                                                  {"y", &Setup::y},
                                                                  {"z", &Setup::z}};
  Setup camera;
  for (int f = 0; f < mxGetNumberOfFields(s); ++f) {
    const std::string field = mxGetFieldNameByNumber(s, f);
    const mxArray* v = mxGetFieldByNumber(s, 0, f);
    const auto number = [&] {
      if (!v || !(mxIsNumeric(v) || mxIsLogical(v)) || mxGetNumberOfElements(v) != 1) {
        call.Fail("camera." + field + " must be a number");
      }
      return mxGetScalar(v);
    };
    const auto size = [&] {
      const double pixels = number();
      if (pixels < 0 || pixels > 100000) call.Fail("camera." + field + " must be a pixel count");
      return static_cast<uint32_t>(pixels);
    };
    if (const auto found = kNumbers.find(field); found != kNumbers.end()) {
      camera.*(found->second) = number();
    } else if (field == "name" || field == "mounted_on") {
      (field == "name" ? camera.name : camera.mounted_on) = call.StringOf(v, ("camera." + field).c_str());
    } else if (field == "width" || field == "height") {
      (field == "width" ? camera.width : camera.height) = size();
    } else if (field == "gimbal") {
      camera.gimbal = number() != 0;
    } else {
      call.Fail("unknown camera field '" + field +
                "' (name, mounted_on, width, height, fov_y_deg, pitch_down_deg, yaw_deg, gimbal, x, y, z)");
    }
  }
  if (camera.name.empty()) call.Fail("the camera needs a name");
  return camera;
}

int64_t MonotonicNs() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return int64_t(t.tv_sec) * 1000000000 + t.tv_nsec;
}

struct Command {
  const char* name;
  int min_args, max_args;
  const char* usage;
  void (*run)(const Call&);
};

const Command kCommands[] = {
    {"connect", 2, 4, "h = sim4cv_mex('connect', address, name [, timeout_ms, protocol_version])",
     [](const Call& c) {
       auto session = std::make_unique<Session>();
       const double timeout = c.Number(2, "timeout_ms", 5000);
       const uint32_t version = c.Has(3) ? c.Id(3, "protocol_version") : 0;  // 0: this build's
       if (timeout < 0) c.Fail("timeout_ms must be >= 0");
       session->client.Connect(c.String(0, "address"), c.String(1, "name"), Ms(static_cast<int64_t>(timeout)), version);
       Sessions()[g_next_handle] = std::move(session);
       c.Return(mxCreateDoubleScalar(g_next_handle++));
     }},
    {"close", 1, 1, "sim4cv_mex('close', h)",
     [](const Call& c) {
       CloseSession(c.Handle());
       Sessions().erase(static_cast<int>(mxGetScalar(c.Arg(0))));
     }},
    {"subscribe", 4, 4,
     "sim4cv_mex('subscribe', h, camera, {'rgb','depth','mask','boxes'}, 'lockstep'|'newest'|'on_request')",
     [](const Call& c) {
       Session& session = c.Handle();
       std::vector<proto::Channel> channels;
       for (const std::string& name : c.StringList(2, "channels")) channels.push_back(ChannelOf(c, name));
       const std::string camera = c.String(1, "camera");
       const proto::Delivery delivery = DeliveryOf(c, c.String(3, "delivery"));
       session.client.Subscribe(camera, channels, delivery);
       session.lockstep_camera = delivery == proto::DELIVERY_LOCKSTEP ? camera : "";
     }},
    {"step", 1, 1, "sim4cv_mex('step', h)", [](const Call& c) { c.Handle().client.Step(); }},
    {"frame", 2, 3, "f = sim4cv_mex('frame', h, 'next'|'step'|'newest' [, timeout_ms])",
     [](const Call& c) {
       Client& client = c.Handle().client;
       const std::string mode = c.String(1, "mode");
       const double timeout_ms = c.Number(2, "timeout_ms", 10000);
       if (timeout_ms < 0) c.Fail("timeout_ms must be >= 0");
       const Ms timeout(static_cast<int64_t>(timeout_ms));
       if (mode == "step") {
         c.Return(sim4cv::mexbind::FrameToStruct(client.StepAndReceive(timeout)));
       } else if (mode == "newest") {
         c.Return(sim4cv::mexbind::FrameToStruct(client.RequestFrame(timeout)));
       } else if (mode == "next") {
         static proto::Frame frame;  // converted at once; its buffers are reused
         if (!client.ReceiveFrame(frame, timeout)) {
           throw sim4cv::ConnectionError("no frame from " + client.address() + " within " +
                                         std::to_string(timeout.count()) + " ms");
         }
         c.Return(sim4cv::mexbind::FrameToStruct(frame));
       } else {
         c.Fail("unknown mode '" + mode + "' (next, step, newest)");
       }
     }},
    {"send_box", 3, 4, "sim4cv_mex('send_box', h, frame_id, [x y w h] [, confidence])",
     [](const Call& c) {
       Client& client = c.Handle().client;
       const mxArray* box = c.Arg(2);
       if (!mxIsDouble(box) || mxIsComplex(box) || mxGetNumberOfElements(box) != 4) c.Fail("the box must be [x y w h]");
       const double* b = static_cast<const double*>(mxGetData(box));
       client.SendTrackerOutput(static_cast<uint64_t>(c.Number(1, "frame_id")), float(b[0]), float(b[1]), float(b[2]),
                                float(b[3]), float(c.Number(3, "confidence", 1.0)));
     }},
    {"controls", 5, 5, "sim4cv_mex('controls', h, entity_id, steering, throttle, brake)",
     [](const Call& c) {
       c.Handle().client.SendControls(c.Id(1, "entity_id"), float(c.Number(2, "steering")),
                                      float(c.Number(3, "throttle")), float(c.Number(4, "brake")));
     }},
    {"state", 1, 1, "s = sim4cv_mex('state', h)",
     [](const Call& c) { c.Return(sim4cv::mexbind::StateToStruct(c.Handle().client.GetState())); }},
    {"load_map", 2, 2, "w = sim4cv_mex('load_map', h, name)",
     [](const Call& c) {
       Client& client = c.Handle().client;
       c.Return(sim4cv::mexbind::WorldToStruct(client.LoadMapByName(c.String(1, "name"))));
     }},
    {"spawn", 6, 7, "id = sim4cv_mex('spawn', h, 'car'|'uav'|'pedestrian', name, x, y, z [, yaw_deg])",
     [](const Call& c) {
       Client& client = c.Handle().client;
       const uint32_t id = client.Spawn(KindOf(c, c.String(1, "kind")), c.String(2, "name"), c.Number(3, "x"),
                                        c.Number(4, "y"), c.Number(5, "z"), c.Number(6, "yaw_deg", 0));
       c.Return(mxCreateDoubleScalar(id));
     }},
    {"add_camera", 2, 2, "w = sim4cv_mex('add_camera', h, struct('name', ..., 'mounted_on', ..., 'width', ..., ...))",
     [](const Call& c) {
       Client& client = c.Handle().client;
       c.Return(sim4cv::mexbind::WorldToStruct(client.AddCamera(CameraOf(c, c.Arg(1)))));
     }},
    {"uav_follow", 3, 5, "w = sim4cv_mex('uav_follow', h, uav_id, target_id [, altitude, pitch_down_deg])",
     [](const Call& c) {
       Client& client = c.Handle().client;
       c.Return(sim4cv::mexbind::WorldToStruct(client.UavFollow(
           c.Id(1, "uav_id"), c.Id(2, "target_id"), c.Number(3, "altitude", 0), c.Number(4, "pitch_down_deg", 0))));
     }},
    {"uav_velocity", 5, 6, "w = sim4cv_mex('uav_velocity', h, uav_id, vx, vy, vz [, yaw_rate_deg])",
     [](const Call& c) {
       Client& client = c.Handle().client;
       c.Return(
           sim4cv::mexbind::WorldToStruct(client.UavVelocity(c.Id(1, "uav_id"), c.Number(2, "vx"), c.Number(3, "vy"),
                                                             c.Number(4, "vz"), c.Number(5, "yaw_rate_deg", 0))));
     }},
    {"world", 1, 1, "w = sim4cv_mex('world', h)",
     [](const Call& c) { c.Return(sim4cv::mexbind::WorldToStruct(c.Handle().client.GetWorld())); }},
    {"now_ns", 0, 0, "t = sim4cv_mex('now_ns')  % int64 CLOCK_MONOTONIC nanoseconds",
     [](const Call& c) {
       mxArray* out = mxCreateNumericMatrix(1, 1, mxINT64_CLASS, mxREAL);
       *static_cast<int64_t*>(mxGetData(out)) = MonotonicNs();
       c.Return(out);
     }},
};

std::string CommandList() {
  std::string out;
  for (const Command& command : kCommands) out += (out.empty() ? "" : ", ") + std::string(command.name);
  return out;
}

void Dispatch(int nlhs, mxArray* plhs[], int nrhs, const mxArray* prhs[]) {
  if (nrhs < 1 || !mxIsChar(prhs[0])) {
    throw BadArgument("the first argument must be a command: " + CommandList());
  }
  char* text = mxArrayToString(prhs[0]);
  const std::string name = text ? text : "";
  mxFree(text);
  for (const Command& command : kCommands) {
    if (name != command.name) continue;
    const Call call(name, command.usage, nrhs - 1, prhs + 1, nlhs, plhs);
    call.Count(command.min_args, command.max_args);
    command.run(call);
    return;
  }
  throw BadArgument("unknown command '" + name + "'; commands: " + CommandList());
}

}  // namespace

void mexFunction(int nlhs, mxArray* plhs[], int nrhs, const mxArray* prhs[]) {
  mexAtExit(CloseAll);  // every call: Octave forgets it when clearing a file it keeps loaded
  // mexErrMsgIdAndTxt does not return (MATLAB may longjmp past destructors),
  // so the error is kept in statics and raised after every local is gone.
  static std::string id, message;
  try {
    Dispatch(nlhs, plhs, nrhs, prhs);
    return;
  } catch (const BadHandle& e) {
    id = "sim4cv:badHandle", message = e.what();
  } catch (const sim4cv::ServerError& e) {
    id = "sim4cv:server", message = proto::ErrorCode_Name(e.code()) + ": " + e.what();
  } catch (const sim4cv::ConnectionError& e) {
    id = "sim4cv:connection", message = e.what();
  } catch (const sim4cv::ShmError& e) {
    id = "sim4cv:connection", message = e.what();
  } catch (const std::invalid_argument& e) {
    id = "sim4cv:badArgument", message = e.what();
  } catch (const std::exception& e) {
    id = "sim4cv:error", message = e.what();
  }
  mexErrMsgIdAndTxt(id.c_str(), "%s", message.c_str());
}
