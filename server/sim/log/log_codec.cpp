#include "server/sim/log/log_codec.h"

#include <limits>
#include <string>

#include "server/common/check.h"
#include "server/sim/log/byte_io.h"
#include "server/sim/log/crc32.h"

namespace sim4cv::runlog::codec {
namespace {

using detail::ByteReader;
using detail::ByteWriter;

// Bytes of one list item on disk (docs/logs.md), for the decoder's count checks.
constexpr std::size_t kEntityBytes = 4 + 13 * 8;
constexpr std::size_t kTrackerBoxBytes = 2 + 4 + 8 + 5 * 4;
constexpr std::size_t kGroundTruthBytes = 2 + 4 + 4 * 4 + 4;
constexpr std::size_t kControlBytes = 4 + 3 * 4 + 1;
constexpr std::size_t kMinLogEntityBytes = 4 + 2 + 2 + 2;
constexpr std::size_t kMinLogCameraBytes = 4 + 4 + 4 + 2;

// Measures a payload through the same field walk that writes it, so the size
// and the layout cannot drift apart. It also does the encoder's checks, as it
// always runs before the writing pass.
class ByteCounter {
 public:
  template <typename T>
  void Put(T) {
    bytes_ += sizeof(T);
  }
  void PutString(const std::string& text) {
    SIM4CV_THROW_UNLESS(
        text.size() <= std::numeric_limits<uint16_t>::max(),
        "run log string of " << text.size() << " bytes is longer than 65535: '" << text.substr(0, 40) << "...'");
    bytes_ += sizeof(uint16_t) + text.size();
  }
  std::size_t bytes() const { return bytes_; }

 private:
  std::size_t bytes_ = 0;
};

template <typename Sink, typename List>
void PutCount(Sink& out, const List& list) {
  SIM4CV_THROW_UNLESS(list.size() <= std::numeric_limits<uint32_t>::max(),
                      "run log list of " << list.size() << " items is too long");
  out.Put(static_cast<uint32_t>(list.size()));
}

template <typename Sink>
void PutBody(Sink& out, const sim::BodyState& body) {
  for (int i = 0; i < 3; ++i) out.Put(body.position[i]);
  out.Put(body.orientation.w());
  out.Put(body.orientation.x());
  out.Put(body.orientation.y());
  out.Put(body.orientation.z());
  for (int i = 0; i < 3; ++i) out.Put(body.linear_velocity[i]);
  for (int i = 0; i < 3; ++i) out.Put(body.angular_velocity[i]);
}

template <typename Sink>
void PutHeader(Sink& out, const RunLogHeader& header) {
  out.Put(header.record_version);
  out.Put(header.created_unix_ns);
  out.PutString(header.creator);
  out.PutString(header.label);
  out.PutString(header.scene_name);
  out.PutString(header.map_path);
  out.Put(header.physics_hz);
  out.Put(header.frame_hz);
  out.Put(header.seed);
  PutCount(out, header.entities);
  for (const LogEntity& entity : header.entities) {
    out.Put(entity.id);
    out.Put(entity.kind);
    out.Put(entity.object_class);
    out.PutString(entity.name);
  }
  PutCount(out, header.cameras);
  for (const LogCamera& camera : header.cameras) {
    out.Put(camera.mounted_on);
    out.Put(camera.width);
    out.Put(camera.height);
    out.PutString(camera.name);
  }
  out.PutString(header.conditions);  // last, so older readers' logs (without it) still decode
}

template <typename Sink>
void PutRecord(Sink& out, const FrameLogRecord& record) {
  out.Put(record.frame_id);
  out.Put(record.sim_time);
  PutCount(out, record.entities);
  for (const EntityLog& entity : record.entities) {
    out.Put(entity.id);
    PutBody(out, entity.body);
  }
  PutCount(out, record.tracker_boxes);
  for (const TrackerBoxLog& t : record.tracker_boxes) {
    out.Put(t.camera);
    out.Put(t.box.client_id);
    out.Put(t.box.frame_id);
    for (float v : {t.box.x, t.box.y, t.box.width, t.box.height, t.box.confidence}) out.Put(v);
  }
  PutCount(out, record.ground_truth);
  for (const GroundTruthBoxLog& g : record.ground_truth) {
    out.Put(g.camera);
    out.Put(g.object_id);
    for (uint32_t v : {g.x, g.y, g.width, g.height}) out.Put(v);
    out.Put(g.visibility);
  }
  PutCount(out, record.controls);
  for (const CarControlLog& c : record.controls) {
    out.Put(c.entity_id);
    for (float v : {c.command.steering, c.command.throttle, c.command.brake}) out.Put(v);
    out.Put(static_cast<uint8_t>(c.command.manual ? 1 : 0));
  }
}

// Writes [u32 length][u32 CRC][payload] at `offset` of `out`, resizing it to
// end there. `fields(sink)` walks the payload; it runs twice (measure, write).
template <typename Fields>
void EncodeFramed(const Fields& fields, std::size_t offset, std::vector<uint8_t>* out) {
  ByteCounter counter;
  fields(counter);
  const std::size_t size = counter.bytes();
  SIM4CV_THROW_UNLESS(size <= kMaxRecordBytes,
                      "run log record of " << size << " bytes is larger than the limit of " << kMaxRecordBytes);
  out->resize(offset + kFrameHeaderBytes + size);
  uint8_t* payload = out->data() + offset + kFrameHeaderBytes;
  ByteWriter writer(payload);
  fields(writer);
  SIM4CV_DEMAND(writer.cursor() == payload + size);
  ByteWriter frame(out->data() + offset);
  frame.Put(static_cast<uint32_t>(size));
  frame.Put(Crc32({payload, size}));
}

bool GetBody(ByteReader& in, sim::BodyState* body) {
  Eigen::Quaterniond& q = body->orientation;
  return in.Get(&body->position.x()) && in.Get(&body->position.y()) && in.Get(&body->position.z()) && in.Get(&q.w()) &&
         in.Get(&q.x()) && in.Get(&q.y()) && in.Get(&q.z()) && in.Get(&body->linear_velocity.x()) &&
         in.Get(&body->linear_velocity.y()) && in.Get(&body->linear_velocity.z()) &&
         in.Get(&body->angular_velocity.x()) && in.Get(&body->angular_velocity.y()) &&
         in.Get(&body->angular_velocity.z());
}

bool GetTrackerBox(ByteReader& in, TrackerBoxLog* t) {
  sim::TrackerReport& b = t->box;
  return in.Get(&t->camera) && in.Get(&b.client_id) && in.Get(&b.frame_id) && in.Get(&b.x) && in.Get(&b.y) &&
         in.Get(&b.width) && in.Get(&b.height) && in.Get(&b.confidence);
}

bool GetGroundTruth(ByteReader& in, GroundTruthBoxLog* g) {
  return in.Get(&g->camera) && in.Get(&g->object_id) && in.Get(&g->x) && in.Get(&g->y) && in.Get(&g->width) &&
         in.Get(&g->height) && in.Get(&g->visibility);
}

bool GetControl(ByteReader& in, CarControlLog* c) {
  uint8_t manual = 0;
  if (!(in.Get(&c->entity_id) && in.Get(&c->command.steering) && in.Get(&c->command.throttle) &&
        in.Get(&c->command.brake) && in.Get(&manual) && manual <= 1)) {
    return false;
  }
  c->command.manual = manual == 1;
  return true;
}

// Reads a u32 count, sizes `list` to it (keeping capacity) and decodes each item.
template <typename List, typename GetItem>
bool GetList(ByteReader& in, std::size_t min_item_bytes, List* list, const GetItem& get_item) {
  uint32_t count = 0;
  if (!in.GetCount(min_item_bytes, &count)) return false;
  list->resize(count);
  for (auto& item : *list) {
    if (!get_item(in, &item)) return false;
  }
  return true;
}

}  // namespace

void EncodeFileStart(const RunLogHeader& header, std::vector<uint8_t>* out) {
  EncodeFramed([&](auto& sink) { PutHeader(sink, header); }, kPreambleBytes, out);
  ByteWriter preamble(out->data());
  for (char c : kMagic) preamble.Put(static_cast<uint8_t>(c));
  preamble.Put(kFormatVersion);
}

void EncodeRecord(const FrameLogRecord& record, std::vector<uint8_t>* out) {
  EncodeFramed([&](auto& sink) { PutRecord(sink, record); }, 0, out);
}

bool DecodeHeader(std::span<const uint8_t> payload, RunLogHeader* out) {
  ByteReader in(payload);
  const auto get_entity = [](ByteReader& r, LogEntity* e) {
    return r.Get(&e->id) && r.Get(&e->kind) && r.Get(&e->object_class) && r.GetString(&e->name);
  };
  const auto get_camera = [](ByteReader& r, LogCamera* c) {
    return r.Get(&c->mounted_on) && r.Get(&c->width) && r.Get(&c->height) && r.GetString(&c->name);
  };
  return in.Get(&out->record_version) && in.Get(&out->created_unix_ns) && in.GetString(&out->creator) &&
         in.GetString(&out->label) && in.GetString(&out->scene_name) && in.GetString(&out->map_path) &&
         in.Get(&out->physics_hz) && in.Get(&out->frame_hz) && in.Get(&out->seed) &&
         GetList(in, kMinLogEntityBytes, &out->entities, get_entity) &&
         GetList(in, kMinLogCameraBytes, &out->cameras, get_camera) &&
         (in.remaining() == 0 || in.GetString(&out->conditions)) && in.remaining() == 0;
}

bool DecodeRecord(std::span<const uint8_t> payload, FrameLogRecord* out) {
  ByteReader in(payload);
  const auto get_entity = [](ByteReader& r, EntityLog* e) { return r.Get(&e->id) && GetBody(r, &e->body); };
  return in.Get(&out->frame_id) && in.Get(&out->sim_time) && GetList(in, kEntityBytes, &out->entities, get_entity) &&
         GetList(in, kTrackerBoxBytes, &out->tracker_boxes, GetTrackerBox) &&
         GetList(in, kGroundTruthBytes, &out->ground_truth, GetGroundTruth) &&
         GetList(in, kControlBytes, &out->controls, GetControl) && in.remaining() == 0;
}

FrameView ReadFrame(std::span<const uint8_t> bytes, std::size_t min_payload) {
  FrameView view;
  ByteReader in(bytes);
  uint32_t length = 0, crc = 0;
  if (!in.Get(&length) || !in.Get(&crc)) return view;  // kTruncated
  if (length < min_payload || length > kMaxRecordBytes) {
    view.status = FrameStatus::kBadLength;
    return view;
  }
  if (in.remaining() < length) return view;  // kTruncated
  const auto payload = bytes.subspan(kFrameHeaderBytes, length);
  if (Crc32(payload) != crc) {
    view.status = FrameStatus::kBadCrc;
    return view;
  }
  view.status = FrameStatus::kOk;
  view.payload = payload;
  view.frame_bytes = kFrameHeaderBytes + length;
  return view;
}

const char* FrameStatusName(FrameStatus status) {
  switch (status) {
    case FrameStatus::kOk:
      return "ok";
    case FrameStatus::kTruncated:
      return "runs past the end of the file";
    case FrameStatus::kBadLength:
      return "implausible length";
    case FrameStatus::kBadCrc:
      return "CRC mismatch";
  }
  return "?";
}

}  // namespace sim4cv::runlog::codec
