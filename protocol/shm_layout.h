/* The byte layout of sim4cvd's shared memory (--shm-name): a frame object
 * (one header and a ring of frame slots: one writer, lock-free readers, a
 * seqlock per slot) that clients can map only read-only, and one area per
 * client (its request ring to the daemon and its response ring back), both
 * memfds the daemon hands over a Unix socket. docs/protocol.md section 13
 * documents every byte and the protocols; this header is the one definition
 * the daemon and the C++ client share, and it is plain C11 as well as C++ so
 * other languages can be checked against it.
 *
 * All integers and floats are little-endian (the memory never leaves the
 * host); every struct has explicit padding and fixed offsets, asserted below.
 * Fields written while others read are accessed atomically (C11 atomics /
 * std::atomic_ref); the rest are written once at creation. */
#ifndef SIM4CV_PROTOCOL_SHM_LAYOUT_H_
#define SIM4CV_PROTOCOL_SHM_LAYOUT_H_

#ifdef __cplusplus
#include <cstddef>
#include <cstdint>
#define SIM4CV_SHM_STATIC_ASSERT(condition, message) static_assert(condition, message)
#define SIM4CV_SHM_CONSTANT(name, value) inline constexpr uint32_t name = value;
namespace sim4cv::shm {
#else
#include <stddef.h>
#include <stdint.h>
#define SIM4CV_SHM_STATIC_ASSERT(condition, message) _Static_assert(condition, message)
#define SIM4CV_SHM_CONSTANT(name, value) enum { name = value };
#endif

/* ShmHeader.magic: these 8 ASCII bytes, no terminating NUL. */
#define SIM4CV_SHM_MAGIC "SIM4CVSM"

/* Bumped whenever any offset, size or protocol rule below changes.
 * 2: one read-only frame object plus one writable area per client, both
 *    memfds handed over a Unix socket (the reply ring and response area of
 *    version 1, which every client could write, are gone).
 * 3: room for 8 channel records (the channel table of protocol/channels.h:
 *    semantic, normals and flow joined RGB, depth and mask); each record
 *    names its element type and components; boxes and entities moved down.
 * 4: a response longer than a response message travels on the attachment's
 *    Unix socket, announced in the response ring (ShmResponseMessage.on_socket). */
SIM4CV_SHM_CONSTANT(kShmLayoutVersion, 4)
SIM4CV_SHM_CONSTANT(kShmHeaderBytes, 512)
/* Frame slot: this many bytes of ShmFrameHeader region, then the pixels. */
SIM4CV_SHM_CONSTANT(kShmFrameHeaderBytes, 8192)
SIM4CV_SHM_CONSTANT(kShmMaxChannels, 8)
SIM4CV_SHM_CONSTANT(kShmMaxBoxes, 128)
SIM4CV_SHM_CONSTANT(kShmMaxEntities, 8)
/* A client's area: its header, its request ring (client -> daemon, one
 * Envelope per slot) and its response ring (daemon -> client). */
SIM4CV_SHM_CONSTANT(kShmAreaHeaderBytes, 256)
SIM4CV_SHM_CONSTANT(kShmRequestSlotBytes, 256)
SIM4CV_SHM_CONSTANT(kShmRequestDataBytes, 248)
SIM4CV_SHM_CONSTANT(kShmRequestCapacity, 64)
SIM4CV_SHM_CONSTANT(kShmResponseMessageBytes, 2048)
SIM4CV_SHM_CONSTANT(kShmResponseDataBytes, 1984)
SIM4CV_SHM_CONSTANT(kShmResponseDepth, 8)
/* A response longer than kShmResponseDataBytes (a Welcome naming many
 * entities, say) is sent on the client's Unix socket instead: one message of
 * an 8-byte response number and at most this many bytes of Envelope. 128 KiB
 * fits the kernel's default socket buffer; a longer response is an Error. */
SIM4CV_SHM_CONSTANT(kShmSocketResponseBytes, 131072)
SIM4CV_SHM_CONSTANT(kShmSocketResponseHeaderBytes, 8)
/* The attach message the daemon sends on the Unix socket. */
SIM4CV_SHM_CONSTANT(kShmAttachBytes, 256)
/* Every slot, entry and pixel plane starts on a multiple of this. */
SIM4CV_SHM_CONSTANT(kShmAlignment, 64)
/* Channel masks hold bit (1 << proto Channel) per pixel channel; which
 * channels exist, their order in a slot and their sizes are the table of
 * docs/protocol.md section 13.2 (protocol/channels.h in C++). */

/* ShmAreaHeader.magic and ShmAttach.magic. */
#define SIM4CV_SHM_AREA_MAGIC "SIM4CVCA"
#define SIM4CV_SHM_ATTACH_MAGIC "SIM4CVAT"

/* The frame object starts with this header (512 bytes). Clients can map the
 * object only read-only (it is sealed with F_SEAL_FUTURE_WRITE): every field
 * is written by the daemon. Lines of 64 bytes group fields by how often they
 * change. */
typedef struct ShmHeader {
  /* Line 0: written once at creation. */
  char magic[8];               /*   0: SIM4CV_SHM_MAGIC */
  uint32_t layout_version;     /*   8: kShmLayoutVersion */
  uint32_t header_bytes;       /*  12: kShmHeaderBytes */
  uint64_t total_bytes;        /*  16: size of the whole object */
  uint32_t slot_count;         /*  24: frame slots in the ring (>= 2) */
  uint32_t frame_header_bytes; /*  28: kShmFrameHeaderBytes */
  uint64_t slot_bytes;         /*  32: bytes per frame slot (multiple of 4096) */
  uint64_t slots_offset;       /*  40: offset of frame slot 0 */
  uint32_t camera_width;       /*  48: pixels */
  uint32_t camera_height;      /*  52: pixels */
  uint32_t writer_pid;         /*  56: the daemon's process id */
  uint32_t max_boxes;          /*  60: kShmMaxBoxes */
  /* Line 1: written once at creation. */
  char camera_name[32];        /*  64: NUL-terminated, the camera of the frames */
  uint8_t reserved1[32];       /*  96 */
  /* Line 2: written once at creation. */
  uint32_t reserved2a;         /* 128 */
  uint32_t max_entities;       /* 132: kShmMaxEntities */
  uint32_t expiry_ms;          /* 136: a client silent this long is disconnected */
  uint32_t protocol_version;   /* 140: the Envelope protocol version (Hello) */
  uint64_t reserved2b;         /* 144 */
  /* Bit (1 << channel) per pixel channel the slots carry (--shm-channels). */
  uint32_t channel_mask;       /* 152 */
  uint8_t reserved2[36];       /* 156 */
  /* Line 3: the frame writer (the daemon's sim thread). */
  uint64_t published;          /* 192: frames published; the newest is in slot (published-1) % slot_count */
  uint64_t newest_frame_id;    /* 200: frame_id of that frame (0: none yet) */
  uint32_t frame_futex;        /* 208: +1 per published frame; readers FUTEX_WAIT on it */
  uint32_t reserved3a;         /* 212 */
  uint32_t closed;             /* 216: 1 once the daemon stopped: no more frames or responses */
  uint8_t reserved3[36];       /* 220 */
  /* Lines 4 to 7. */
  uint8_t reserved4[256];      /* 256 */
} ShmHeader;

/* One pixel channel of a frame slot. */
typedef struct ShmChannel {
  uint32_t channel;         /*  0: proto Channel (1 RGB, 2 DEPTH, 3 MASK, 5 SEMANTIC, 6 NORMALS, 7 FLOW) */
  uint32_t format;          /*  4: proto PixelFormat */
  uint32_t stride;          /*  8: bytes per row */
  uint16_t bytes_per_pixel; /* 12: components * element bytes */
  uint8_t element;          /* 14: proto ElementType: 1 uint8, 2 uint16, 3 float32 */
  uint8_t components;       /* 15: per pixel */
  uint64_t offset;          /* 16: from the start of the slot; a multiple of 64 */
  uint64_t bytes;           /* 24: height * stride */
} ShmChannel;

/* A ground-truth box; the fields of proto Box. */
typedef struct ShmBox {
  uint32_t object_id;      /*  0 */
  uint32_t object_class;   /*  4: proto ObjectClass */
  uint32_t x;              /*  8 */
  uint32_t y;              /* 12 */
  uint32_t width;          /* 16 */
  uint32_t height;         /* 20 */
  float visibility;        /* 24 */
  uint32_t visible_pixels; /* 28 */
} ShmBox;

/* An entity's pose and velocity; the fields of proto EntityState but name. */
typedef struct ShmEntityPose {
  uint32_t id;                 /*   0 */
  uint32_t kind;               /*   4: proto EntityKind */
  double position[3];          /*   8: x, y, z, metres */
  double orientation[4];       /*  32: w, x, y, z */
  double linear_velocity[3];   /*  64: m/s */
  double angular_velocity[3];  /*  88: rad/s */
} ShmEntityPose;

/* The first 8192 bytes of each frame slot; the pixels follow. */
typedef struct ShmFrameHeader {
  uint64_t sequence;           /*    0: seqlock: odd while the writer changes the slot */
  uint64_t publication;        /*    8: ShmHeader.published value this slot was written as */
  uint64_t frame_id;           /*   16 */
  double sim_time;             /*   24: seconds */
  int64_t render_end_mono_ns;  /*   32: CLOCK_MONOTONIC */
  uint32_t width;              /*   40 */
  uint32_t height;             /*   44 */
  uint32_t channel_mask;       /*   48: bit (1 << channel) per channel present (= ShmHeader.channel_mask) */
  uint32_t channel_count;      /*   52: records in channels[]: one per pixel channel of the table, in its order; an absent one is all zero */
  uint32_t box_count;          /*   56: entries used in boxes[] */
  uint32_t box_total;          /*   60: visible labelled objects (> box_count if truncated) */
  uint32_t entity_count;       /*   64: entries used in entities[] */
  uint32_t camera_index;       /*   68: index of the camera in Welcome.cameras */
  uint8_t reserved0[56];       /*   72 */
  ShmChannel channels[8];      /*  128: the table's pixel channels in its order (zero if absent), then unused */
  ShmBox boxes[128];           /*  384: ordered by object_id */
  ShmEntityPose entities[8];   /* 4480: ordered by id */
  uint8_t reserved1[2816];     /* 5376 */
} ShmFrameHeader;

/* The start of a client's area (256 bytes): one per attached client, mapped
 * read-write by that client and by the daemon, which never reads its
 * layout back from it (docs/protocol.md 13.5). */
typedef struct ShmAreaHeader {
  /* Line 0: written once by the daemon. */
  char magic[8];                   /*   0: SIM4CV_SHM_AREA_MAGIC */
  uint32_t layout_version;         /*   8: kShmLayoutVersion */
  uint32_t header_bytes;           /*  12: kShmAreaHeaderBytes */
  uint64_t total_bytes;            /*  16: size of the area */
  uint64_t request_offset;         /*  24: offset of request slot 0 */
  uint32_t request_capacity;       /*  32: kShmRequestCapacity */
  uint32_t request_slot_bytes;     /*  36: kShmRequestSlotBytes */
  uint64_t response_offset;        /*  40: offset of response message 0 */
  uint32_t response_depth;         /*  48: kShmResponseDepth */
  uint32_t response_message_bytes; /*  52: kShmResponseMessageBytes */
  uint8_t reserved0[8];            /*  56 */
  /* Line 1: the client. */
  uint64_t request_write;          /*  64: requests written; request n is in slot n % request_capacity */
  uint8_t reserved1[56];           /*  72 */
  /* Line 2: the daemon. */
  uint64_t request_read;           /* 128: requests the daemon has taken (their slots are free again) */
  uint64_t responses_written;      /* 136: response k is in message k % response_depth */
  uint32_t response_futex;         /* 144: +1 per response written (and when the area is closed) */
  uint32_t closed;                 /* 148: 1 once the daemon ended this client's attachment */
  uint8_t reserved2[40];           /* 152 */
  /* Line 3. */
  uint8_t reserved3[64];           /* 192 */
} ShmAreaHeader;

/* One client -> daemon request (256 bytes). */
typedef struct ShmRequestSlot {
  uint32_t size;       /*  0: bytes of data used (<= kShmRequestDataBytes) */
  uint32_t reserved;   /*  4 */
  uint8_t data[248];   /*  8: one serialized Envelope */
} ShmRequestSlot;

/* One daemon -> client response (2048 bytes). */
typedef struct ShmResponseMessage {
  uint64_t sequence;     /*  0: 2k+1 while response k is written, 2k+2 once complete */
  uint32_t size;         /*  8: bytes of the Envelope (in data, or on the socket) */
  /* 0: data holds the Envelope. 1: it was too long for data, so it is the
   * client's next socket message tagged with k (kShmSocketResponseBytes);
   * the daemon sent it before writing this message. */
  uint32_t on_socket;    /* 12 */
  uint8_t reserved[48];  /* 16 */
  uint8_t data[1984];    /* 64: one serialized Envelope (on_socket 0) */
} ShmResponseMessage;

/* The first message the daemon sends on a client's Unix socket (256 bytes).
 * With status 0 it carries three descriptors (SCM_RIGHTS): the frame
 * object, the client's area and its doorbell (an eventfd). Later messages
 * are long responses: a little-endian u64 response number k, then the
 * Envelope (ShmResponseMessage.on_socket). */
typedef struct ShmAttach {
  char magic[8];           /*   0: SIM4CV_SHM_ATTACH_MAGIC */
  uint32_t layout_version; /*   8: kShmLayoutVersion */
  uint32_t status;         /*  12: 0 attached; 1 refused (no descriptors; see message) */
  uint64_t frames_bytes;   /*  16: size of the frame object */
  uint64_t area_bytes;     /*  24: size of the client's area */
  char message[224];       /*  32: NUL-terminated reason when refused */
} ShmAttach;

SIM4CV_SHM_STATIC_ASSERT(sizeof(double) == 8 && sizeof(float) == 4, "IEEE-754 binary64/binary32 expected");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmHeader) == 512, "ShmHeader is 512 bytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmHeader, camera_name) == 64, "ShmHeader line 1");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmHeader, max_entities) == 132, "ShmHeader.max_entities");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmHeader, channel_mask) == 152, "ShmHeader.channel_mask");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmHeader, published) == 192, "ShmHeader line 3");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmHeader, frame_futex) == 208, "ShmHeader.frame_futex");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmHeader, closed) == 216, "ShmHeader.closed");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmHeader, reserved4) == 256, "ShmHeader line 4");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmChannel) == 32, "ShmChannel is 32 bytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmChannel, element) == 14, "ShmChannel.element");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmChannel, offset) == 16, "ShmChannel.offset");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmBox) == 32, "ShmBox is 32 bytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmBox, visibility) == 24, "ShmBox.visibility");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmEntityPose) == 112, "ShmEntityPose is 112 bytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmEntityPose, position) == 8, "ShmEntityPose.position");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmEntityPose, orientation) == 32, "ShmEntityPose.orientation");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmEntityPose, linear_velocity) == 64, "ShmEntityPose.linear_velocity");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmEntityPose, angular_velocity) == 88, "ShmEntityPose.angular_velocity");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmFrameHeader) == 8192, "ShmFrameHeader is kShmFrameHeaderBytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmFrameHeader, sim_time) == 24, "ShmFrameHeader.sim_time");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmFrameHeader, width) == 40, "ShmFrameHeader.width");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmFrameHeader, camera_index) == 68, "ShmFrameHeader.camera_index");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmFrameHeader, channels) == 128, "ShmFrameHeader.channels");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmFrameHeader, boxes) == 384, "ShmFrameHeader.boxes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmFrameHeader, entities) == 4480, "ShmFrameHeader.entities");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmFrameHeader, reserved1) == 5376, "ShmFrameHeader.reserved1");

SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmAreaHeader) == 256, "ShmAreaHeader is kShmAreaHeaderBytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmAreaHeader, request_write) == 64, "ShmAreaHeader line 1");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmAreaHeader, request_read) == 128, "ShmAreaHeader line 2");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmAreaHeader, response_futex) == 144, "ShmAreaHeader.response_futex");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmAreaHeader, closed) == 148, "ShmAreaHeader.closed");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmRequestSlot) == 256, "ShmRequestSlot is kShmRequestSlotBytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmRequestSlot, data) == 8, "ShmRequestSlot.data");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmResponseMessage) == 2048, "ShmResponseMessage is kShmResponseMessageBytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmResponseMessage, on_socket) == 12, "ShmResponseMessage.on_socket");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmResponseMessage, data) == 64, "ShmResponseMessage.data");
SIM4CV_SHM_STATIC_ASSERT(sizeof(ShmAttach) == 256, "ShmAttach is kShmAttachBytes");
SIM4CV_SHM_STATIC_ASSERT(offsetof(ShmAttach, message) == 32, "ShmAttach.message");

#ifdef __cplusplus
static_assert(kShmMaxChannels == 8 && kShmMaxBoxes == 128 && kShmMaxEntities == 8, "array sizes above");
}  // namespace sim4cv::shm
#endif

#undef SIM4CV_SHM_CONSTANT
#undef SIM4CV_SHM_STATIC_ASSERT

#endif /* SIM4CV_PROTOCOL_SHM_LAYOUT_H_ */
