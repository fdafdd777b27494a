// Session logic of sim4cv::Client: handshake, request/response matching and
// the frame receive path. Socket details live in socket_io.cpp.
#include "sim4cv/client.h"

#include <google/protobuf/io/coded_stream.h>
#include <unistd.h>

#include <algorithm>
#include <climits>

#include "requests.h"
#include "socket_io.h"

namespace sim4cv {
namespace {

using Envelope = proto::Envelope;

// First byte of an Envelope that carries a Frame (field number, wire type 2).
constexpr uint8_t kFrameFieldTag = (Envelope::kFrameFieldNumber << 3) | 2;

detail::Deadline DeadlineAfter(Client::Duration timeout) { return std::chrono::steady_clock::now() + timeout; }

std::string TimeoutMessage(const char* awaited, Client::Duration timeout, const std::string& peer) {
  return "timed out after " + std::to_string(timeout.count()) + " ms waiting for " + awaited + " from sim4cvd at " +
         peer;
}

}  // namespace

ServerError::ServerError(proto::ErrorCode code, const std::string& message, bool fatal, uint32_t request_id)
    : std::runtime_error(message), code_(code), fatal_(fatal), request_id_(request_id) {}

std::optional<ImageView> FindImage(const proto::Frame& frame, proto::Channel channel) {
  for (const proto::Image& image : frame.images()) {
    if (image.channel() != channel) continue;
    // A view that promises more bytes than the frame holds would let callers
    // read past the buffer, so a short image is a broken peer, not a view.
    if (image.data().size() < static_cast<std::size_t>(image.stride()) * frame.height()) {
      throw ConnectionError("frame " + std::to_string(frame.frame_id()) + ": " + proto::Channel_Name(channel) +
                            " carries " + std::to_string(image.data().size()) + " bytes, fewer than stride " +
                            std::to_string(image.stride()) + " x height " + std::to_string(frame.height()));
    }
    return ImageView{reinterpret_cast<const uint8_t*>(image.data().data()),
                     frame.width(),
                     frame.height(),
                     image.stride(),
                     image.format(),
                     image.element(),
                     image.components()};
  }
  return std::nullopt;
}

Client::~Client() { Close(); }

void Client::ConnectRaw(const std::string& host, uint16_t port, Duration timeout) {
  Close();
  welcome_.Clear();
  fd_ = detail::ConnectTcp(host, port, DeadlineAfter(timeout));
  peer_ = host + ":" + std::to_string(port);
}

void Client::Connect(const std::string& host, uint16_t port, const std::string& client_name, Duration timeout,
                     uint32_t protocol_version) {
  // One deadline for connecting and the handshake: the caller's timeout
  // bounds the whole call.
  const detail::Deadline deadline = DeadlineAfter(timeout);
  ConnectRaw(host, port, timeout);
  try {
    const Envelope hello = detail::HelloRequest(client_name, protocol_version);
    SendEnvelope(hello);
    Envelope reply;
    if (!ReceiveKind(Envelope::kWelcome, reply, deadline)) {
      throw ConnectionError(TimeoutMessage("Welcome", timeout, peer_));
    }
    welcome_ = std::move(*reply.mutable_welcome());
  } catch (...) {
    Close();  // a half-done handshake leaves nothing usable
    throw;
  }
}

void Client::Subscribe(const std::string& camera, const std::vector<proto::Channel>& channels, proto::Delivery delivery,
                       bool with_state, Duration timeout) {
  const detail::Deadline deadline = DeadlineAfter(timeout);
  const Envelope request = detail::SubscribeRequest(camera, channels, delivery, with_state);
  SendEnvelope(request);
  Envelope reply;
  if (!ReceiveKind(Envelope::kSubscribed, reply, deadline)) {
    throw ConnectionError(TimeoutMessage("Subscribed", timeout, peer_));
  }
  // The daemon sends Subscribed before any frame of the new subscription, so
  // every frame queued by now belongs to the one it replaced.
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_frame(); });
}

void Client::Step() {
  SendEnvelope(detail::StepRequest());
}

bool Client::ReceiveFrame(proto::Frame& frame, Duration timeout) {
  if (!ReceiveKind(Envelope::kFrame, scratch_, DeadlineAfter(timeout))) return false;
  // Swapping hands the pixels over without a copy and leaves the caller's
  // previous frame in scratch_, whose buffers the next parse fills in place.
  frame.Swap(scratch_.mutable_frame());
  return true;
}

const proto::Frame& Client::StepAndReceive(Duration timeout) {
  Step();
  if (!ReceiveFrame(frame_, timeout)) throw ConnectionError(TimeoutMessage("a Frame", timeout, peer_));
  return frame_;
}

const proto::Frame& Client::RequestFrame(Duration timeout) {
  proto::Envelope request;
  request.mutable_next_frame();
  SendEnvelope(request);
  if (!ReceiveFrame(frame_, timeout)) throw ConnectionError(TimeoutMessage("a requested Frame", timeout, peer_));
  return frame_;
}

void Client::SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence) {
  SendEnvelope(detail::TrackerOutputRequest(frame_id, x, y, width, height, confidence));
}

void Client::SendControls(uint32_t entity_id, float steering, float throttle, float brake) {
  SendEnvelope(detail::ControlsRequest(entity_id, steering, throttle, brake));
}

proto::State Client::GetState(Duration timeout) {
  const detail::Deadline deadline = DeadlineAfter(timeout);
  Envelope reply;
  // A queued State answers a request already made; asking again would leave
  // every later GetState one answer behind.
  const bool queued = std::any_of(pending_.begin(), pending_.end(), [](const Envelope& e) { return e.has_state(); });
  if (!queued) {
    Envelope request;
    request.mutable_get_state();
    SendEnvelope(request);
  }
  if (!ReceiveKind(Envelope::kState, reply, deadline)) throw ConnectionError(TimeoutMessage("State", timeout, peer_));
  return std::move(*reply.mutable_state());
}

proto::Configured Client::Configure(proto::Configure request, Duration timeout) {
  const detail::Deadline deadline = DeadlineAfter(timeout);
  if (++last_request_id_ == 0) ++last_request_id_;  // 0 could not be told apart from other Errors
  const uint32_t id = last_request_id_;
  request.set_request_id(id);
  Envelope envelope;
  *envelope.mutable_configure() = std::move(request);
  SendEnvelope(envelope);
  const auto answer = [id](const Envelope& e) {
    return (e.has_configured() && e.configured().request_id() == id) || (e.has_error() && e.error().request_id() == id);
  };
  Envelope reply;
  if (!ReceiveMatching(answer, /*errors_interrupt=*/false, reply, deadline)) {
    throw ConnectionError(TimeoutMessage("Configured", timeout, peer_));
  }
  if (reply.has_error()) ThrowServerError(reply.error());
  return std::move(*reply.mutable_configured());
}

proto::WorldInfo Client::ConfigureWorld(proto::Configure request) {
  return std::move(*Configure(std::move(request)).mutable_world());
}

proto::WorldInfo Client::LoadMapByName(const std::string& name, const std::string& route, float car_speed,
                                       const std::optional<proto::TrafficSettings>& traffic) {
  return ConfigureWorld(detail::LoadMapByNameRequest(name, route, car_speed, traffic));
}

proto::WorldInfo Client::LoadMapText(const std::string& text, const std::string& route, float car_speed,
                                     const std::optional<proto::TrafficSettings>& traffic) {
  return ConfigureWorld(detail::LoadMapTextRequest(text, route, car_speed, traffic));
}

uint32_t Client::Spawn(proto::EntityKind kind, const std::string& name, double x, double y, double z, double yaw_deg,
                       bool snap_to_lane) {
  return Configure(detail::SpawnRequest(kind, name, x, y, z, yaw_deg, snap_to_lane)).entity_id();
}

proto::WorldInfo Client::Remove(uint32_t entity_id) { return ConfigureWorld(detail::RemoveRequest(entity_id)); }

proto::WorldInfo Client::SetRoute(uint32_t entity_id, const std::string& route_name, float speed) {
  return ConfigureWorld(detail::SetRouteRequest(entity_id, route_name, speed));
}

proto::WorldInfo Client::SetWaypoints(uint32_t entity_id, const std::vector<std::array<double, 2>>& points, bool closed,
                                      float speed) {
  return ConfigureWorld(detail::SetWaypointsRequest(entity_id, points, closed, speed));
}

proto::WorldInfo Client::SetSpeed(uint32_t entity_id, float speed) {
  return ConfigureWorld(detail::SetSpeedRequest(entity_id, speed));
}

proto::WorldInfo Client::UavFollow(uint32_t uav_id, uint32_t target_id, double altitude, double pitch_down_deg) {
  return ConfigureWorld(detail::UavFollowRequest(uav_id, target_id, altitude, pitch_down_deg));
}

proto::WorldInfo Client::UavHold(uint32_t uav_id, double x, double y, double z, double yaw_deg) {
  return ConfigureWorld(detail::UavHoldRequest(uav_id, x, y, z, yaw_deg));
}

proto::WorldInfo Client::UavVelocity(uint32_t uav_id, double vx, double vy, double vz, double yaw_rate_deg) {
  return ConfigureWorld(detail::UavVelocityRequest(uav_id, vx, vy, vz, yaw_rate_deg));
}

proto::WorldInfo Client::AddCamera(const CameraSetup& camera) { return ConfigureWorld(detail::AddCameraRequest(camera)); }

proto::WorldInfo Client::RemoveCamera(const std::string& name) {
  return ConfigureWorld(detail::RemoveCameraRequest(name));
}

proto::WorldInfo Client::Reset() { return ConfigureWorld(detail::ResetRequest()); }

proto::WorldInfo Client::GetWorld() { return ConfigureWorld(detail::GetWorldRequest()); }

proto::WorldInfo Client::SetEffects(const proto::CameraEffects& effects) {
  proto::Configure request;
  *request.mutable_set_effects() = effects;
  return ConfigureWorld(std::move(request));
}

proto::WorldInfo Client::SetConditions(const std::string& preset, std::optional<double> hour,
                                       const std::string& quality) {
  return ConfigureWorld(detail::SetConditionsRequest(preset, hour, quality));
}

proto::RoadQueryResult Client::QueryRoad(double x, double y, uint32_t count, double step,
                                         std::optional<double> heading_deg) {
  return std::move(*Configure(detail::QueryRoadRequest(x, y, count, step, heading_deg)).mutable_road());
}

void Client::SendEnvelope(const Envelope& envelope) {
  RequireConnected();
  const std::size_t body_size = envelope.ByteSizeLong();
  if (body_size > UINT32_MAX) throw std::length_error("envelope of " + std::to_string(body_size) + " bytes");
  // Prefix and body in one buffer so that each envelope is one send().
  send_buffer_.resize(wire::kLengthPrefixBytes + body_size);
  auto* bytes = reinterpret_cast<uint8_t*>(send_buffer_.data());
  wire::EncodeLengthPrefix(static_cast<uint32_t>(body_size), bytes);
  envelope.SerializeWithCachedSizesToArray(bytes + wire::kLengthPrefixBytes);
  SendRaw(bytes, send_buffer_.size());
}

void Client::SendRaw(const void* data, std::size_t size) {
  RequireConnected();
  try {
    detail::WriteAll(fd_, data, size, peer_);
  } catch (const ConnectionError&) {
    Close();
    throw;
  }
}

bool Client::ReceiveEnvelope(Envelope& envelope, Duration timeout) {
  if (!pending_.empty()) {
    envelope.Swap(&pending_.front());
    pending_.pop_front();
    return true;
  }
  if (!ReadEnvelope(DeadlineAfter(timeout))) return false;
  envelope.Swap(&scratch_);
  return true;
}

void Client::Close() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  pending_.clear();
  prefix_filled_ = 0;
  body_filled_ = 0;
}

bool Client::ReceiveKind(Envelope::KindCase kind, Envelope& out, Deadline deadline) {
  return ReceiveMatching([kind](const Envelope& e) { return e.kind_case() == kind; }, /*errors_interrupt=*/true, out,
                         deadline);
}

template <typename Wanted>
bool Client::ReceiveMatching(const Wanted& wanted, bool errors_interrupt, Envelope& out, Deadline deadline) {
  // Only Configure queues Errors (those that are not its answer); whoever
  // waits next meets them in arrival order.
  const auto stops = [&](const Envelope& e) { return wanted(e) || (errors_interrupt && e.has_error()); };
  if (detail::TakeQueuedIf(pending_, stops, out)) {
    if (!wanted(out)) ThrowServerError(out.error());
    return true;
  }
  while (ReadEnvelope(deadline)) {
    if (wanted(scratch_)) {
      if (&out != &scratch_) out.Swap(&scratch_);
      return true;
    }
    if (scratch_.has_error() && (errors_interrupt || scratch_.error().fatal())) ThrowServerError(scratch_.error());
    pending_.push_back(std::move(scratch_));
  }
  return false;
}

bool Client::ReadEnvelope(Deadline deadline) {
  RequireConnected();
  try {
    if (prefix_filled_ < wire::kLengthPrefixBytes) {
      if (detail::ReadUntil(fd_, prefix_, sizeof prefix_, prefix_filled_, deadline, peer_) ==
          detail::ReadStatus::kTimeout) {
        return false;
      }
      body_size_ = wire::DecodeLengthPrefix(prefix_);
      // CodedInputStream takes an int size, so INT_MAX caps any limit.
      if (body_size_ > std::min<std::size_t>(max_message_bytes_, INT_MAX)) {
        FailConnection("sim4cvd announced a message of " + std::to_string(body_size_) +
                       " bytes, more than the limit of " + std::to_string(max_message_bytes_));
      }
      // Grow only: resizing down and up again would zero-fill each time.
      if (buffer_.size() < body_size_) buffer_.resize(body_size_);
      body_filled_ = 0;
    }
    if (detail::ReadUntil(fd_, reinterpret_cast<uint8_t*>(buffer_.data()), body_size_, body_filled_, deadline, peer_) ==
        detail::ReadStatus::kTimeout) {
      return false;
    }
  } catch (const ConnectionError&) {
    Close();
    throw;
  }
  prefix_filled_ = 0;
  ParseScratch(body_size_);
  return true;
}

void Client::ParseScratch(std::size_t size) {
  // Envelope::Clear() would delete the Frame in its oneof. Clearing only the
  // Frame keeps its images' byte buffers and repeated elements allocated, so
  // a frame like the last one parses without touching the heap. It is only
  // safe when the new envelope is a frame too, which its first byte tells.
  const bool reuse_frame = scratch_.has_frame() && size > 0 && static_cast<uint8_t>(buffer_[0]) == kFrameFieldTag;
  if (reuse_frame) {
    scratch_.mutable_frame()->Clear();
  } else {
    scratch_.Clear();
  }
  google::protobuf::io::CodedInputStream input(reinterpret_cast<const uint8_t*>(buffer_.data()),
                                               static_cast<int>(size));
  if (!scratch_.MergePartialFromCodedStream(&input) || !input.ConsumedEntireMessage()) {
    FailConnection("sim4cvd sent " + std::to_string(size) + " bytes that are not a valid Envelope");
  }
}

void Client::ThrowServerError(const proto::Error& error) {
  if (error.fatal()) Close();
  throw ServerError(error.code(), error.message(), error.fatal(), error.request_id());
}

void Client::FailConnection(const std::string& what) {
  Close();
  throw ConnectionError(what + " (" + peer_ + ")");
}

void Client::RequireConnected() const {
  if (fd_ < 0) throw ConnectionError("not connected to sim4cvd" + (peer_.empty() ? "" : " at " + peer_));
}

}  // namespace sim4cv
