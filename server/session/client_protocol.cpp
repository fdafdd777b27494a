#include "server/session/client_protocol.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "protocol/framing.h"
#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/common/quoted.h"
#include "server/session/access_token.h"
#include "server/session/configure_check.h"

namespace sim4cv::session {
namespace {

using Outcome = ClientProtocol::Outcome;

// Empty if `value` is finite and within [low, high]; otherwise the complaint.
std::string CheckRange(const char* field, double value, double low, double high) {
  if (std::isfinite(value) && value >= low && value <= high) return {};
  std::ostringstream message;
  message << field << " is " << value << "; it must be a finite number in [" << low << ", " << high << "]";
  return message.str();
}

std::string CheckFinite(const char* field, double value) {
  if (std::isfinite(value)) return {};
  std::ostringstream message;
  message << field << " is " << value << "; it must be a finite number";
  return message.str();
}

}  // namespace

ClientProtocol::ClientProtocol(ClientId client, const ServerContext& context, std::shared_ptr<ClientLink> link,
                               FrameMailbox* mailbox)
    : client_(client), context_(context), link_(std::move(link)), mailbox_(mailbox) {}

Outcome ClientProtocol::Refuse(proto::ErrorCode code, const std::string& message, bool fatal, proto::Envelope& reply) {
  proto::Error* error = reply.mutable_error();
  error->set_code(code);
  error->set_message(message);
  error->set_fatal(fatal);
  return fatal ? Outcome::kReplyAndClose : Outcome::kReply;
}

Outcome ClientProtocol::Handle(const proto::Envelope& request, proto::Envelope& reply) {
  reply.Clear();
  using Kind = proto::Envelope::KindCase;
  const Kind kind = request.kind_case();
  if (kind == Kind::KIND_NOT_SET) {
    return Refuse(proto::ERROR_CODE_UNEXPECTED_MESSAGE,
                  "the envelope carries no message (empty oneof, or a field number this server does not know)", true,
                  reply);
  }
  if (!handshaken_ && kind != Kind::kHello) {
    return Refuse(proto::ERROR_CODE_NOT_HANDSHAKEN,
                  "the first message must be Hello; got field " + std::to_string(static_cast<int>(kind)) +
                      " before the handshake",
                  true, reply);
  }
  switch (kind) {
    case Kind::kHello:
      return HandleHello(request.hello(), reply);
    case Kind::kSubscribe:
      return HandleSubscribe(request.subscribe(), reply);
    case Kind::kStep:
      return HandleStep(reply);
    case Kind::kNextFrame:
      return HandleNextFrame(reply);
    case Kind::kControls:
      return HandleControls(request.controls(), reply);
    case Kind::kTrackerOutput:
      return HandleTrackerOutput(request.tracker_output(), reply);
    case Kind::kGetState:
      return HandleGetState(reply);
    case Kind::kGetStats:
      return HandleGetStats(reply);
    case Kind::kConfigure:
      return HandleConfigure(request.configure(), reply);
    default:
      return Refuse(proto::ERROR_CODE_UNEXPECTED_MESSAGE,
                    "envelope field " + std::to_string(static_cast<int>(kind)) +
                        " is a message only the server sends; clients send Hello, Subscribe, Step, TrackerOutput, "
                        "Controls, GetState, GetStats or Configure",
                    true, reply);
  }
}

void ClientProtocol::FillWelcome(const ServerContext& context, ClientId client, proto::Welcome& welcome) {
  welcome = context.welcome;
  welcome.set_client_id(client);
  // The world may have changed since the daemon started (Configure).
  proto::WorldInfo world = context.world.Get();
  welcome.set_scene_name(world.scene_name());
  welcome.mutable_cameras()->Swap(world.mutable_cameras());
  welcome.mutable_entities()->Swap(world.mutable_entities());
}

Outcome ClientProtocol::HandleHello(const proto::Hello& hello, proto::Envelope& reply) {
  if (handshaken_) {
    return Refuse(proto::ERROR_CODE_INVALID_STATE, "Hello was already accepted on this connection; send it only once",
                  false, reply);
  }
  if (hello.protocol_version() != wire::kProtocolVersion) {
    return Refuse(proto::ERROR_CODE_VERSION_MISMATCH,
                  "client speaks protocol version " + std::to_string(hello.protocol_version()) +
                      " but this server speaks version " + std::to_string(wire::kProtocolVersion) +
                      "; use a client built for version " + std::to_string(wire::kProtocolVersion),
                  true, reply);
  }
  if (hello.client_name().size() > limits::kMaxNameBytes) {
    // Fatal, as every Hello that cannot be accepted: a UDP peer is registered only by its Welcome.
    return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                  "Hello.client_name is " + std::to_string(hello.client_name().size()) + " bytes long; at most " +
                      std::to_string(limits::kMaxNameBytes) + " (limits::kMaxNameBytes); connect with a shorter name",
                  true, reply);
  }
  if (const std::string problem = RefuseToken(hello); !problem.empty()) {
    return Refuse(proto::ERROR_CODE_UNAUTHENTICATED, problem, true, reply);
  }
  handshaken_ = true;
  client_name_ = hello.client_name();
  FillWelcome(context_, client_, *reply.mutable_welcome());
  LOG_INFO("client " << client_ << " (" << Quoted(client_name_) << ") completed the handshake");
  return Outcome::kReply;
}

std::string ClientProtocol::RefuseToken(const proto::Hello& hello) const {
  const std::string& expected = context_.access_token;
  if (expected.empty() || authenticated_ || TokenMatches(hello.token(), expected)) return {};
  LOG_INFO("client " << client_ << " (" << Quoted(hello.client_name()) << ") refused: "
                     << (hello.token().empty() ? "no access token" : "a wrong access token"));
  return std::string(hello.token().empty() ? "Hello carries no access token (Hello.token)"
                                           : "Hello.token is not this daemon's access token") +
         "; sim4cvd admits only clients that show it (docs/security.md). It is in " + context_.access_token_file +
         ", readable only by the daemon's user, whose clients read it by themselves for local addresses; "
         "elsewhere set SIM4CV_TOKEN to its content";
}

Outcome ClientProtocol::HandleSubscribe(const proto::Subscribe& subscribe, proto::Envelope& reply) {
  if (subscribe.camera().size() > limits::kMaxNameBytes) {
    return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                  "Subscribe.camera " + Quoted(subscribe.camera()) + " is longer than any camera name (at most " +
                      std::to_string(limits::kMaxNameBytes) +
                      " bytes, limits::kMaxNameBytes); use a name from Welcome.cameras",
                  false, reply);
  }
  std::string camera_names;
  const int camera = context_.world.FindCamera(subscribe.camera(), camera_names);
  if (camera < 0) {
    return Refuse(proto::ERROR_CODE_UNKNOWN_CAMERA,
                  "no camera named " + Quoted(subscribe.camera()) + "; this scene has " + camera_names, false, reply);
  }
  if (subscribe.channels_size() == 0) {
    return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT, "Subscribe.channels is empty; ask for at least one channel",
                  false, reply);
  }
  if (subscribe.channels_size() > channels::kSubscribableCount) {
    return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                  "Subscribe.channels has " + std::to_string(subscribe.channels_size()) + " entries; at most " +
                      std::to_string(channels::kSubscribableCount) + ", each channel once: " + channels::ValidList(),
                  false, reply);
  }
  channels::ChannelSet seen = 0;
  for (int channel : subscribe.channels()) {
    if (!channels::Subscribable(channel)) {
      return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                    "Subscribe.channels holds " + std::to_string(channel) +
                        ", which is no channel this daemon serves; valid channels are " + channels::ValidList(),
                    false, reply);
    }
    if (channels::Has(seen, channel)) {
      return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                    "Subscribe.channels lists " + proto::Channel_Name(channel) + " twice", false, reply);
    }
    seen |= channels::Bit(channel);
  }
  const proto::Delivery delivery = subscribe.delivery();
  if (delivery != proto::DELIVERY_LOCKSTEP && delivery != proto::DELIVERY_NEWEST &&
      delivery != proto::DELIVERY_ON_REQUEST) {
    return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                  "Subscribe.delivery is " + std::to_string(delivery) +
                      "; use DELIVERY_LOCKSTEP (1), DELIVERY_NEWEST (2) or DELIVERY_ON_REQUEST (3)",
                  false, reply);
  }
  if (delivery == proto::DELIVERY_LOCKSTEP && context_.mode != proto::SIM_MODE_LOCKSTEP) {
    return Refuse(proto::ERROR_CODE_INVALID_STATE,
                  "lockstep delivery needs a daemon started with --mode lockstep; this one runs in realtime mode, "
                  "so subscribe with DELIVERY_NEWEST",
                  false, reply);
  }
  const double max_fps = subscribe.max_fps();
  if (!(max_fps >= 0 && max_fps <= limits::kMaxSubscribeFps)) {  // also NaN
    return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                  "Subscribe.max_fps is " + std::to_string(max_fps) + "; give 0 (every frame) to " +
                      std::to_string(static_cast<int>(limits::kMaxSubscribeFps)) + " frames per second",
                  false, reply);
  }
  if (max_fps > 0 && delivery == proto::DELIVERY_LOCKSTEP) {
    return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                  "Subscribe.max_fps caps DELIVERY_NEWEST and DELIVERY_ON_REQUEST; a lockstep subscriber gets every "
                  "frame it Steps for, so leave max_fps 0",
                  false, reply);
  }
  subscribed_ = true;
  with_state_ = subscribe.with_state();
  camera_index_ = static_cast<uint32_t>(camera);
  outstanding_steps_ = 0;
  frame_requested_ = false;
  subscription_.set_camera(subscribe.camera());
  *subscription_.mutable_channels() = subscribe.channels();
  subscription_.set_delivery(delivery);
  subscription_.set_max_fps(max_fps);
  std::shared_ptr<const MailboxGate> gate;
  if (mailbox_) {
    mailbox_->Reset(delivery, &context_.commands);
    gate = mailbox_->gate();
  }
  const int64_t min_interval_ns = max_fps > 0 ? static_cast<int64_t>(1e9 / max_fps) : 0;
  context_.commands.Post({client_, SubscribeCommand{static_cast<uint32_t>(camera), delivery, seen, link_.lock(),
                                                    std::move(gate), min_interval_ns}});
  *reply.mutable_subscribed() = subscription_;
  return Outcome::kReply;
}

// Nothing to answer: the frame is the answer, sent by the transport when
// one is waiting (ClientSession::NextFrame).
Outcome ClientProtocol::HandleNextFrame(proto::Envelope& reply) {
  if (!on_request()) {
    return Refuse(proto::ERROR_CODE_INVALID_STATE,
                  "NextFrame needs an on-request subscription; send Subscribe with DELIVERY_ON_REQUEST first", false,
                  reply);
  }
  frame_requested_ = true;
  return Outcome::kNoReply;
}

Outcome ClientProtocol::HandleStep(proto::Envelope& reply) {
  if (!subscribed_ || subscription_.delivery() != proto::DELIVERY_LOCKSTEP) {
    return Refuse(proto::ERROR_CODE_INVALID_STATE,
                  "Step needs a lockstep subscription; send Subscribe with DELIVERY_LOCKSTEP first", false, reply);
  }
  if (outstanding_steps_ >= FrameMailbox::kMaxLockstepBacklog) {
    return Refuse(proto::ERROR_CODE_INVALID_STATE,
                  std::to_string(outstanding_steps_) + " Steps are already waiting for their frames (limit " +
                      std::to_string(FrameMailbox::kMaxLockstepBacklog) + "); read frames before stepping further",
                  false, reply);
  }
  ++outstanding_steps_;
  context_.commands.Post({client_, StepCommand{}});
  return Outcome::kNoReply;
}

Outcome ClientProtocol::HandleControls(const proto::Controls& controls, proto::Envelope& reply) {
  for (const std::string& problem : {CheckRange("Controls.steering", controls.steering(), -1, 1),
                                     CheckRange("Controls.throttle", controls.throttle(), 0, 1),
                                     CheckRange("Controls.brake", controls.brake(), 0, 1)}) {
    if (!problem.empty()) return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT, problem, false, reply);
  }
  // Whether entity_id is a car the sim thread checks, and answers an Error through the link if not.
  if (!context_.commands.TryPost({client_, ControlsCommand{controls.entity_id(), controls.steering(),
                                                           controls.throttle(), controls.brake(), link_.lock()}})) {
    return RefuseBusy("Controls", reply);
  }
  return Outcome::kNoReply;
}

Outcome ClientProtocol::HandleTrackerOutput(const proto::TrackerOutput& output, proto::Envelope& reply) {
  const proto::ImageBox& box = output.box();
  for (const std::string& problem :
       {CheckFinite("TrackerOutput.box.x", box.x()), CheckFinite("TrackerOutput.box.y", box.y()),
        CheckRange("TrackerOutput.box.width", box.width(), 1e-6, 1e9),
        CheckRange("TrackerOutput.box.height", box.height(), 1e-6, 1e9),
        CheckRange("TrackerOutput.confidence", output.confidence(), 0, 1)}) {
    if (!problem.empty()) return Refuse(proto::ERROR_CODE_INVALID_ARGUMENT, problem, false, reply);
  }
  if (!context_.commands.TryPost({client_, TrackerOutputCommand{output.frame_id(), box.x(), box.y(), box.width(),
                                                                box.height(), output.confidence(), link_.lock()}})) {
    return RefuseBusy("TrackerOutput", reply);
  }
  return Outcome::kNoReply;
}

Outcome ClientProtocol::RefuseBusy(const char* what, proto::Envelope& reply) {
  return Refuse(proto::ERROR_CODE_INVALID_STATE,
                std::string("this ") + what + " was dropped: " + std::to_string(limits::kMaxQueuedCommands) +
                    " commands already wait for the simulation (limits::kMaxQueuedCommands); send at most one per "
                    "frame",
                false, reply);
}

Outcome ClientProtocol::HandleGetState(proto::Envelope& reply) {
  proto::State* state = reply.mutable_state();
  const StateRef snapshot = context_.latest_state.Get();
  if (!snapshot) return Outcome::kReply;  // before the first step: an empty State at frame 0
  *state = snapshot->state;
  for (std::size_t i = 0; i < snapshot->tracker_clients.size(); ++i) {
    if (snapshot->tracker_clients[i] == client_) *state->mutable_last_tracker_output() = snapshot->tracker_outputs[i];
  }
  return Outcome::kReply;
}

Outcome ClientProtocol::HandleGetStats(proto::Envelope& reply) {
  auto& counters = *reply.mutable_stats()->mutable_counters();
  for (const auto& [name, value] : context_.counters.Snapshot()) counters[name] = value;
  return Outcome::kReply;
}

Outcome ClientProtocol::HandleConfigure(const proto::Configure& request, proto::Envelope& reply) {
  // The sim thread carries out every posted request before its next frame:
  // without a bound, one client's pipelined requests stall every client.
  const uint32_t outstanding = outstanding_configures_->load(std::memory_order_acquire);
  if (outstanding >= limits::kMaxOutstandingConfigures) {
    Refuse(proto::ERROR_CODE_INVALID_STATE,
           "Configure " + std::to_string(request.request_id()) + " refused: " + std::to_string(outstanding) +
               " Configure requests of this connection are still waiting for their answers (at most " +
               std::to_string(limits::kMaxOutstandingConfigures) +
               ", limits::kMaxOutstandingConfigures); wait for the answers before sending more",
           false, reply);
    reply.mutable_error()->set_request_id(request.request_id());
    return Outcome::kReply;
  }
  if (const std::string problem = CheckConfigure(request); !problem.empty()) {
    Refuse(proto::ERROR_CODE_INVALID_ARGUMENT, problem, false, reply);
    reply.mutable_error()->set_request_id(request.request_id());
    return Outcome::kReply;
  }
  outstanding_configures_->fetch_add(1, std::memory_order_acq_rel);
  auto answer = std::make_shared<ConfigureReplyLink>(link_.lock(), outstanding_configures_);
  context_.commands.Post({client_, ConfigureCommand{request, std::move(answer)}});
  return Outcome::kNoReply;
}

void ClientProtocol::OnFramesSent(uint64_t count) { outstanding_steps_ -= std::min(count, outstanding_steps_); }

void ClientProtocol::Disconnect() {
  if (disconnected_) return;
  disconnected_ = true;
  context_.commands.Post({client_, DisconnectCommand{}});
}

}  // namespace sim4cv::session
