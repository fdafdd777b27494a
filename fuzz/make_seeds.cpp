// Writes the seed corpora of the fuzz targets from real messages, built with
// the protocol's own code: sim4cv_fuzz_seeds SOURCE_DIR OUT_DIR writes
// OUT_DIR/<target>/<seed>. scripts/fuzz.sh seeds runs it into fuzz/corpus;
// the run-log seed is recorded by the daemon instead (scripts/fuzz.sh).
#include <sys/uio.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "fuzz/fuzz_input.h"
#include "protocol/framing.h"
#include "server/transport/shm/shm_client_area.h"
#include "server/transport/udp/frame_chunker.h"
#include "sim4cv.pb.h"

namespace {

namespace fs = std::filesystem;
using sim4cv::proto::Envelope;
using sim4cv::proto::Configure;

fs::path out_dir;
fs::path source_dir;

void Write(const std::string& target, const std::string& name, const std::string& bytes) {
  fs::create_directories(out_dir / target);
  std::ofstream(out_dir / target / name, std::ios::binary) << bytes;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

Envelope Hello(const std::string& name) {
  Envelope e;
  e.mutable_hello()->set_protocol_version(sim4cv::wire::kProtocolVersion);
  e.mutable_hello()->set_client_name(name);
  return e;
}

Envelope Subscribe(const std::string& camera, sim4cv::proto::Delivery delivery) {
  Envelope e;
  auto* s = e.mutable_subscribe();
  s->set_camera(camera);
  for (auto c : {sim4cv::proto::CHANNEL_RGB, sim4cv::proto::CHANNEL_DEPTH, sim4cv::proto::CHANNEL_MASK,
                 sim4cv::proto::CHANNEL_BOXES}) {
    s->add_channels(c);
  }
  s->set_delivery(delivery);
  s->set_with_state(true);
  return e;
}

// The session a tracker runs: handshake, subscribe, then steps with controls and reports.
std::vector<Envelope> TrackerSession(sim4cv::proto::Delivery delivery) {
  std::vector<Envelope> session = {Hello("fuzz-seed"), Subscribe("uav", delivery)};
  for (uint64_t i = 1; i <= 2; ++i) {
    Envelope step;
    step.mutable_step();
    step.set_sequence(3 * i);
    session.push_back(step);
    Envelope controls;
    auto* c = controls.mutable_controls();
    c->set_entity_id(1);
    c->set_steering(0.1f);
    c->set_throttle(0.5f);
    c->set_brake(0.0f);
    controls.set_sequence(3 * i + 1);
    session.push_back(controls);
    Envelope report;
    auto* t = report.mutable_tracker_output();
    t->set_frame_id(i);
    t->mutable_box()->set_x(10);
    t->mutable_box()->set_y(20);
    t->mutable_box()->set_width(30);
    t->mutable_box()->set_height(40);
    t->set_confidence(0.9f);
    report.set_sequence(3 * i + 2);
    session.push_back(report);
  }
  Envelope get_state, get_stats;
  get_state.mutable_get_state();
  get_stats.mutable_get_stats();
  session.push_back(get_state);
  session.push_back(get_stats);
  return session;
}

// One Configure of each kind (docs/protocol.md §16), named.
std::vector<std::pair<std::string, Configure>> Configures() {
  std::vector<std::pair<std::string, Configure>> all;
  auto add = [&](const std::string& name) -> Configure& {
    all.emplace_back(name, Configure());
    all.back().second.set_request_id(static_cast<uint32_t>(all.size()));
    return all.back().second;
  };
  {
    auto* load = add("load_map_name").mutable_load_map();
    load->set_name("tracking/easy_desert");
    load->set_route("loop");
    load->set_car_speed(8);
  }
  {
    auto* load = add("load_map_text").mutable_load_map();
    load->set_text(ReadFile(source_dir / "scenes/tracking/easy_desert.map"));
    load->mutable_traffic()->set_cars(3);
    load->mutable_traffic()->set_parked(2);
    load->mutable_traffic()->set_pedestrians(2);
    load->mutable_traffic()->set_seed(7);
  }
  {
    auto* spawn = add("spawn").mutable_spawn();
    spawn->set_kind(sim4cv::proto::ENTITY_KIND_CAR);
    spawn->set_name("car2");
    spawn->mutable_position()->set_x(5);
    spawn->mutable_position()->set_y(-3);
    spawn->set_yaw_deg(90);
    spawn->set_snap_to_lane(true);
  }
  add("remove").mutable_remove()->set_entity_id(3);
  {
    auto* route = add("set_route_waypoints").mutable_set_route();
    route->set_entity_id(1);
    for (int i = 0; i < 4; ++i) {
      auto* p = route->mutable_waypoints()->add_points();
      p->set_x(10.0 * (i % 2));
      p->set_y(10.0 * (i / 2));
    }
    route->mutable_waypoints()->set_closed(true);
    route->set_speed(6);
  }
  {
    auto* route = add("set_route_name").mutable_set_route();
    route->set_entity_id(1);
    route->set_route_name("loop");
  }
  {
    auto* uav = add("command_uav_follow").mutable_command_uav();
    uav->set_entity_id(2);
    uav->mutable_follow()->set_target_id(1);
    uav->mutable_follow()->set_altitude(20);
    uav->mutable_follow()->set_pitch_down_deg(45);
  }
  {
    auto* uav = add("command_uav_hold").mutable_command_uav();
    uav->set_entity_id(2);
    uav->mutable_hold()->mutable_position()->set_z(30);
    uav->mutable_hold()->set_yaw_deg(10);
  }
  {
    auto* uav = add("command_uav_velocity").mutable_command_uav();
    uav->set_entity_id(2);
    uav->mutable_velocity()->mutable_velocity()->set_x(2);
    uav->mutable_velocity()->set_yaw_rate_deg(5);
  }
  {
    auto* camera = add("add_camera").mutable_add_camera();
    camera->set_name("rear");
    camera->set_mounted_on("car");
    camera->set_width(320);
    camera->set_height(180);
    camera->set_fov_y_deg(60);
    camera->set_pitch_down_deg(10);
    camera->set_yaw_deg(180);
    camera->mutable_offset()->set_z(1.5);
  }
  add("remove_camera").mutable_remove_camera()->set_name("rear");
  add("reset").mutable_reset();
  add("get_world").mutable_get_world();
  {
    auto* query = add("query_road").mutable_query_road();
    query->mutable_point()->set_x(3);
    query->set_heading_deg(90);
    query->set_use_heading(true);
    query->set_count(5);
    query->set_step(2);
  }
  return all;
}

std::string Framed(const std::vector<Envelope>& messages) {
  std::string stream;
  for (const Envelope& e : messages) {
    const std::string body = e.SerializeAsString();
    uint8_t prefix[sim4cv::wire::kLengthPrefixBytes];
    sim4cv::wire::EncodeLengthPrefix(static_cast<uint32_t>(body.size()), prefix);
    stream.append(reinterpret_cast<const char*>(prefix), sizeof prefix);
    stream += body;
  }
  return stream;
}

// UDP datagrams for fuzz_udp_datagram: a sender byte, then the Envelope.
std::string Datagrams(const std::vector<Envelope>& messages, uint8_t sender) {
  std::string records;
  for (const Envelope& e : messages) sim4cv::fuzz::AppendRecord(records, char(sender) + e.SerializeAsString());
  return records;
}

void EnvelopeAndUdpSeeds() {
  Write("fuzz_envelope", "hello", Framed({Hello("tracker")}));
  Write("fuzz_envelope", "session_lockstep", Framed(TrackerSession(sim4cv::proto::DELIVERY_LOCKSTEP)));
  Write("fuzz_envelope", "session_newest", Framed(TrackerSession(sim4cv::proto::DELIVERY_NEWEST)));
  Write("fuzz_udp_datagram", "session_lockstep", Datagrams(TrackerSession(sim4cv::proto::DELIVERY_LOCKSTEP), 0));
  std::string two_clients = Datagrams(TrackerSession(sim4cv::proto::DELIVERY_NEWEST), 1);
  two_clients += Datagrams({Hello("second"), Envelope(), Subscribe("chase", sim4cv::proto::DELIVERY_NEWEST)}, 2);
  Write("fuzz_udp_datagram", "two_clients_keepalive", two_clients);
  std::string configures_udp;
  std::vector<Envelope> configures = {Hello("configurer")};
  for (const auto& [name, configure] : Configures()) {
    Write("fuzz_configure", name, configure.SerializeAsString());
    Envelope e;
    *e.mutable_configure() = configure;
    Write("fuzz_envelope", "configure_" + name, Framed({Hello("configurer"), e}));
    configures.push_back(e);
  }
  Write("fuzz_udp_datagram", "configures", Datagrams(configures, 3));
}

// A small real frame, chunked by the daemon's own FrameChunker.
void ReassemblerSeeds() {
  Envelope frame;
  auto* f = frame.mutable_frame();
  f->set_frame_id(42);
  f->set_sim_time(1.4);
  f->set_camera("uav");
  f->set_width(8);
  f->set_height(4);
  auto* image = f->add_images();
  image->set_channel(sim4cv::proto::CHANNEL_RGB);
  image->set_stride(24);
  image->set_data(std::string(96, '\x7f'));
  auto* box = f->add_boxes();
  box->set_x(1);
  box->set_width(3);
  const std::string encoded = frame.SerializeAsString();
  const sim4cv::transport::Segment segment{reinterpret_cast<const uint8_t*>(encoded.data()), encoded.size()};
  for (std::size_t datagram_bytes : {std::size_t{64}, std::size_t{1472}}) {
    sim4cv::transport::FrameChunker chunker(datagram_bytes);
    chunker.Start(42, {&segment, 1}, encoded.size());
    std::string records;
    for (uint32_t i = 0; i < chunker.chunk_count(); ++i) {
      sim4cv::transport::FrameChunker::Header header;
      iovec iov[sim4cv::transport::FrameChunker::kMaxIovecs];
      const std::size_t count = chunker.Build(i, header, iov);
      std::string datagram;
      for (std::size_t k = 0; k < count; ++k) datagram.append(static_cast<const char*>(iov[k].iov_base), iov[k].iov_len);
      sim4cv::fuzz::AppendRecord(records, datagram);
    }
    Envelope welcome;
    welcome.mutable_welcome()->set_client_id(3);
    sim4cv::fuzz::AppendRecord(records, welcome.SerializeAsString());
    Write("fuzz_udp_reassembler", "frame_in_" + std::to_string(chunker.chunk_count()) + "_chunks", records);
  }
}

// Client areas as a client leaves them: the daemon's header, then requests.
void ShmSeeds() {
  for (int requests : {0, 3, 64}) {
    sim4cv::transport::ShmClientArea area(-1);  // no socket: only requests are written
    const sim4cv::shm::AreaMap& map = area.map();
    std::vector<Envelope> session = TrackerSession(sim4cv::proto::DELIVERY_NEWEST);
    for (int n = 0; n < requests; ++n) {
      const std::string body = session[static_cast<std::size_t>(n) % session.size()].SerializeAsString();
      sim4cv::shm::ShmRequestSlot& slot = map.request(static_cast<uint64_t>(n));
      slot.size = static_cast<uint32_t>(body.size());
      std::memcpy(slot.data, body.data(), body.size());
    }
    map.header().request_write = static_cast<uint64_t>(requests);
    const std::size_t used = sim4cv::shm::kAreaRequestOffset +
                             static_cast<std::size_t>(requests) * sim4cv::shm::kShmRequestSlotBytes;
    Write("fuzz_shm", "requests_" + std::to_string(requests),
          std::string(reinterpret_cast<const char*>(map.base()), used));
  }
}

void MapSeeds() {
  // Every tracking map and one driving pair: each surroundings, routes open and closed, objects.
  for (const char* map : {"scenes/tracking/easy_desert.map", "scenes/tracking/easy_urban.map",
                          "scenes/tracking/hard_desert.map", "scenes/tracking/hard_urban.map",
                          "scenes/driving/train/01_desert.map", "scenes/driving/train/01_urban.map"}) {
    const fs::path path(map);
    Write("fuzz_map", path.parent_path().filename().string() + "_" + path.filename().string(),
          ReadFile(source_dir / path));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: sim4cv_fuzz_seeds SOURCE_DIR OUT_DIR\n";
    return 2;
  }
  source_dir = argv[1];
  out_dir = argv[2];
  EnvelopeAndUdpSeeds();
  ReassemblerSeeds();
  ShmSeeds();
  MapSeeds();
  return 0;
}
