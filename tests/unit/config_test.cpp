// Unit tests of the daemon's command-line flags (server/daemon/config.*).
#include "server/daemon/config.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "tests/support/no_warnings.h"

namespace sim4cv::daemon {
namespace {

Config Parse(const std::vector<std::string>& args) {
  std::string help;
  const std::optional<Config> config = ParseFlags(args, help);
  EXPECT_TRUE(config.has_value());
  EXPECT_TRUE(help.empty());
  return config.value_or(Config{});
}

// Parses expecting std::invalid_argument; returns its message.
std::string ParseError(const std::vector<std::string>& args) {
  std::string help;
  try {
    ParseFlags(args, help);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  std::string joined;
  for (const auto& a : args) joined += a + " ";
  ADD_FAILURE() << "no std::invalid_argument for: " << joined;
  return {};
}

void ExpectMentions(const std::string& message, const std::vector<std::string>& parts) {
  for (const auto& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos) << "message '" << message << "' lacks '" << part << "'";
  }
}

TEST(ConfigTest, Defaults) {
  const Config config = Parse({});
  EXPECT_EQ(config.scene_file, "");
  EXPECT_EQ(config.seed, 1u);
  EXPECT_EQ(config.bind_address, "127.0.0.1");
  EXPECT_EQ(config.tcp_port, 0);
  EXPECT_EQ(config.physics_hz, 240.0);
  EXPECT_EQ(config.frame_hz, 30.0);
  EXPECT_EQ(config.width, 320u);
  EXPECT_EQ(config.height, 180u);
  EXPECT_EQ(config.mode, proto::SIM_MODE_LOCKSTEP);
  EXPECT_EQ(config.max_message_bytes, 2u << 20);
  EXPECT_EQ(config.max_clients, 64u);
  EXPECT_EQ(config.tcp_send_buffer_bytes, 256u << 10);
  EXPECT_EQ(config.udp_port, 0);
  EXPECT_EQ(config.udp_datagram_bytes, 65000u);
  EXPECT_EQ(config.udp_expiry_ms, 5000u);
  EXPECT_EQ(config.shm_name, "");
  EXPECT_EQ(config.handshake_timeout_ms, 10000u);
  EXPECT_EQ(config.message_timeout_ms, 10000u);
  EXPECT_EQ(config.idle_timeout_ms, 0u);
  EXPECT_EQ(config.shm_camera, "uav");
  EXPECT_EQ(config.shm_slots, 8u);
  EXPECT_EQ(config.shm_channel_mask, 0x0eu) << "RGB, depth and mask, as before the flag existed";
  EXPECT_EQ(config.log_level, "info");
  EXPECT_EQ(config.substeps_per_frame(), 8u);
}

TEST(ConfigTest, EachFlagParses) {
  EXPECT_EQ(Parse({"--scene", "/tmp/town.scene"}).scene_file, "/tmp/town.scene");
  EXPECT_EQ(Parse({"--seed", "18446744073709551615"}).seed, 18446744073709551615ull);
  EXPECT_EQ(Parse({"--seed", "0"}).seed, 0u);
  EXPECT_EQ(Parse({"--bind", "0.0.0.0"}).bind_address, "0.0.0.0");
  EXPECT_EQ(Parse({"--tcp-port", "5555"}).tcp_port, 5555);
  EXPECT_EQ(Parse({"--tcp-port", "65535"}).tcp_port, 65535);
  EXPECT_EQ(Parse({"--physics-hz", "480"}).physics_hz, 480.0);
  EXPECT_EQ(Parse({"--frame-hz", "60"}).frame_hz, 60.0);
  EXPECT_EQ(Parse({"--width", "640"}).width, 640u);
  EXPECT_EQ(Parse({"--height", "16"}).height, 16u);
  EXPECT_EQ(Parse({"--mode", "realtime"}).mode, proto::SIM_MODE_REALTIME);
  EXPECT_EQ(Parse({"--mode", "lockstep"}).mode, proto::SIM_MODE_LOCKSTEP);
  EXPECT_EQ(Parse({"--max-message-bytes", "1048576"}).max_message_bytes, 1048576u);
  EXPECT_EQ(Parse({"--max-clients", "3"}).max_clients, 3u);
  EXPECT_EQ(Parse({"--tcp-send-buffer", "0"}).tcp_send_buffer_bytes, 0u);
  EXPECT_EQ(Parse({"--handshake-timeout-ms", "0"}).handshake_timeout_ms, 0u);
  EXPECT_EQ(Parse({"--message-timeout-ms", "250"}).message_timeout_ms, 250u);
  EXPECT_EQ(Parse({"--idle-timeout-ms", "60000"}).idle_timeout_ms, 60000u);
  EXPECT_EQ(Parse({"--tcp-send-buffer", "1048576"}).tcp_send_buffer_bytes, 1048576u);
  EXPECT_EQ(Parse({"--udp-port", "-1"}).udp_port, -1);
  EXPECT_EQ(Parse({"--udp-port", "6000"}).udp_port, 6000);
  EXPECT_EQ(Parse({"--udp-datagram-bytes", "1472"}).udp_datagram_bytes, 1472u);
  EXPECT_EQ(Parse({"--udp-expiry-ms", "250"}).udp_expiry_ms, 250u);
  EXPECT_EQ(Parse({"--shm-name", "sim4cv_test"}).shm_name, "/sim4cv_test");
  EXPECT_EQ(Parse({"--shm-name", "/already"}).shm_name, "/already");
  EXPECT_EQ(Parse({"--shm-camera", "front"}).shm_camera, "front");
  EXPECT_EQ(Parse({"--shm-slots", "2"}).shm_slots, 2u);
  EXPECT_EQ(Parse({"--shm-channels", "rgb"}).shm_channel_mask, 1u << proto::CHANNEL_RGB);
  for (const char* level : {"debug", "info", "warning", "error"})
    EXPECT_EQ(Parse({"--log-level", level}).log_level, level);
}

TEST(ConfigTest, ManyFlagsTogetherAndTheLastWins) {
  const Config config = Parse({"--width", "100", "--height", "50", "--mode", "realtime", "--width", "200",
                               "--physics-hz", "100", "--frame-hz", "25"});
  EXPECT_EQ(config.width, 200u);
  EXPECT_EQ(config.height, 50u);
  EXPECT_EQ(config.mode, proto::SIM_MODE_REALTIME);
  EXPECT_EQ(config.substeps_per_frame(), 4u);
}

TEST(ConfigTest, RunLogFlags) {
  const Config defaults = Parse({});
  EXPECT_EQ(defaults.log_file, "");
  EXPECT_EQ(defaults.log_label, "");
  EXPECT_EQ(defaults.replay_file, "");
  const Config config = Parse({"--log", "/tmp/run.s4log", "--log-label", "KCF tracker", "--replay", "/tmp/old.s4log"});
  EXPECT_EQ(config.log_file, "/tmp/run.s4log");
  EXPECT_EQ(config.log_label, "KCF tracker");
  EXPECT_EQ(config.replay_file, "/tmp/old.s4log");
  ExpectMentions(ParseError({"--log-label", "x"}), {"--log-label", "--log"});
  ExpectMentions(ParseError({"--log", "a.s4log", "--replay", "a.s4log"}), {"--log", "--replay", "'a.s4log'"});
  EXPECT_EQ(Parse({"--replay", "a.s4log", "--replay-only", "1,3"}).replay_only, (std::vector<uint32_t>{1, 3}));
  ExpectMentions(ParseError({"--replay-only", "1"}), {"--replay-only needs --replay"});
  ExpectMentions(ParseError({"--replay", "a.s4log", "--replay-only", "1,x"}), {"--replay-only", "'x'"});
  ExpectMentions(ParseError({"--replay", "a.s4log", "--replay-only", "0"}), {"--replay-only is 0"});
}

TEST(ConfigTest, TrafficFlags) {
  const Config defaults = Parse({"--seed", "9"});
  EXPECT_EQ(defaults.traffic.moving_cars, 0);
  EXPECT_TRUE(defaults.traffic.traffic_lights);
  EXPECT_EQ(defaults.traffic.seed, 9u) << "the traffic seed follows --seed unless given";
  const Config config =
      Parse({"--traffic-cars", "12", "--traffic-parked", "30", "--traffic-pedestrians", "8", "--traffic-lights", "off",
             "--traffic-seed", "5", "--traffic-green", "6.5", "--traffic-yellow", "1", "--traffic-all-red", "0"});
  EXPECT_EQ(config.traffic.moving_cars, 12);
  EXPECT_EQ(config.traffic.parked_cars, 30);
  EXPECT_EQ(config.traffic.pedestrians, 8);
  EXPECT_FALSE(config.traffic.traffic_lights);
  EXPECT_EQ(config.traffic.seed, 5u);
  EXPECT_EQ(config.traffic.green_s, 6.5);
  EXPECT_EQ(config.traffic.yellow_s, 1.0);
  EXPECT_EQ(config.traffic.all_red_s, 0.0);
  ExpectMentions(ParseError({"--traffic-lights", "maybe"}), {"--traffic-lights", "'maybe'", "on or off"});
  ExpectMentions(ParseError({"--traffic-cars", "-3"}), {"--traffic-cars", "-3"});
}

TEST(ConfigTest, ControlsTimeout) {
  EXPECT_EQ(Parse({}).controls_timeout_ms, 1000u);
  EXPECT_EQ(Parse({"--controls-timeout-ms", "500"}).controls_timeout_ms, 500u);
  EXPECT_EQ(Parse({"--controls-timeout-ms", "0"}).controls_timeout_ms, 0u) << "0 turns it off";
  ExpectMentions(ParseError({"--controls-timeout-ms", "-1"}), {"--controls-timeout-ms is -1", "[0, 86400000]"});
  ExpectMentions(ParseError({"--controls-timeout-ms", "soon"}), {"--controls-timeout-ms expects a number, got 'soon'"});
  ExpectMentions(ParseError({"--controls-timeout-ms", "1.5"}), {"--controls-timeout-ms", "'1.5'"});
  ExpectMentions(ParseError({"--controls-timeout-ms", "86400001"}), {"--controls-timeout-ms is 86400001"});
  ExpectMentions(HelpText(), {"--controls-timeout-ms N", "(default 1000; 0 = never)"});
}

TEST(ConfigTest, MapsDirForLoadMap) {
  EXPECT_NE(Parse({}).maps_dir.find("scenes"), std::string::npos);
  EXPECT_EQ(Parse({"--maps-dir", "/srv/maps"}).maps_dir, "/srv/maps");
}

// The studio's port (docs/studio.md): off unless asked, on loopback unless told.
TEST(ConfigTest, StudioFlags) {
  const Config defaults = Parse({});
  EXPECT_EQ(defaults.http_port, -1);
  EXPECT_EQ(defaults.http_bind, "127.0.0.1");
  EXPECT_EQ(defaults.http_max_clients, 32u);
  EXPECT_NE(defaults.studio_dir.find("studio"), std::string::npos);
  const Config set = Parse(
      {"--http-port", "8080", "--http-bind", "0.0.0.0", "--http-max-clients", "200", "--studio-dir", "/srv/studio"});
  EXPECT_EQ(set.http_port, 8080);
  EXPECT_EQ(set.http_bind, "0.0.0.0");
  EXPECT_EQ(set.http_max_clients, 200u);
  EXPECT_EQ(set.studio_dir, "/srv/studio");
  EXPECT_EQ(Parse({"--http-port", "0"}).http_port, 0) << "0: any free port";
  ExpectMentions(ParseError({"--http-port", "65536"}), {"--http-port is 65536", "[-1, 65535]"});
  ExpectMentions(ParseError({"--http-max-clients", "0"}), {"--http-max-clients is 0"});
  ExpectMentions(HelpText(), {"--http-port N", "--http-bind ADDRESS", "no authentication", "--http-max-clients N",
                              "--studio-dir DIR", "http=PORT"});
}

TEST(ConfigTest, HelpReturnsNulloptWithEveryFlag) {
  for (const char* flag : {"--help", "-h"}) {
    std::string help;
    const auto config = ParseFlags({"--width", "100", flag}, help);
    EXPECT_FALSE(config.has_value());
    ExpectMentions(help, {"--scene",
                          "--seed",
                          "--bind",
                          "--tcp-port",
                          "--physics-hz",
                          "--frame-hz",
                          "--width",
                          "--height",
                          "--mode",
                          "--max-message-bytes",
                          "--max-clients",
                          "--tcp-send-buffer",
                          "--udp-port",
                          "--udp-datagram-bytes",
                          "--udp-expiry-ms",
                          "--shm-name",
                          "--shm-camera",
                          "--shm-slots",
                          "--shm-channels",
                          "--log-level",
                          "--log ",
                          "--log-label",
                          "--replay",
                          "--replay-only",
                          "--maps-dir",
                          "--traffic-cars",
                          "--traffic-parked",
                          "--traffic-pedestrians",
                          "--traffic-lights",
                          "--traffic-green",
                          "--traffic-seed",
                          "--help",
                          "lockstep",
                          "realtime",
                          "--handshake-timeout-ms",
                          "--message-timeout-ms",
                          "--idle-timeout-ms"});
    EXPECT_EQ(help, HelpText());
  }
  // --help wins even before a bad flag.
  std::string help;
  EXPECT_FALSE(ParseFlags({"--help", "--bogus"}, help).has_value());
}

TEST(ConfigTest, ConditionsFlags) {
  const Config defaults = Parse({});
  EXPECT_EQ(defaults.conditions.preset, conditions::Preset::CLEAR_NOON);
  EXPECT_EQ(defaults.conditions.hour, conditions::Info(conditions::Preset::CLEAR_NOON).hour);
  EXPECT_EQ(defaults.conditions.quality, conditions::Quality::kFull);
  const Config rain = Parse({"--conditions", "rain"});
  EXPECT_EQ(rain.conditions.preset, conditions::Preset::RAIN);
  EXPECT_EQ(rain.conditions.hour, conditions::Info(conditions::Preset::RAIN).hour) << "the preset's own hour";
  // --hour wins wherever it stands.
  const Config late = Parse({"--hour", "21.5", "--conditions", "fog", "--quality", "fast"});
  EXPECT_EQ(late.conditions.preset, conditions::Preset::FOG);
  EXPECT_EQ(late.conditions.hour, 21.5);
  EXPECT_EQ(late.conditions.quality, conditions::Quality::kFast);
  ExpectMentions(ParseError({"--conditions", "sunny"}), {"--conditions 'sunny' is not a preset", "clear_noon", "rain"});
  ExpectMentions(ParseError({"--hour", "25"}), {"--hour is 25", "[0, 24]"});
  ExpectMentions(ParseError({"--hour", "-1"}), {"--hour"});
  ExpectMentions(ParseError({"--quality", "medium"}), {"--quality 'medium' is not a quality", "full or fast"});
  const Config noisy =
      Parse({"--noise-read", "2.5", "--noise-shot", "1", "--randomize", "9", "--randomize-every", "30"});
  EXPECT_EQ(noisy.conditions.noise_read, 2.5);
  EXPECT_EQ(noisy.conditions.noise_shot, 1.0);
  EXPECT_EQ(noisy.randomize_seed, 9u);
  EXPECT_EQ(noisy.randomize_every_frames, 30u);
  ExpectMentions(ParseError({"--noise-read", "60"}), {"--noise-read is 60", "[0, 50]"});
  ExpectMentions(ParseError({"--noise-shot", "-1"}), {"--noise-shot"});
  ExpectMentions(ParseError({"--randomize-every", "5"}), {"--randomize-every needs --randomize SEED"});
}

TEST(ConfigTest, UnknownFlagIsNamed) {
  ExpectMentions(ParseError({"--widht", "100"}), {"unknown flag '--widht'", "--help"});
  ExpectMentions(ParseError({"width", "100"}), {"unknown flag 'width'"});
  ExpectMentions(ParseError({"--width=100"}), {"'--width=100'"});
}

TEST(ConfigTest, MissingValueIsNamed) {
  ExpectMentions(ParseError({"--width"}), {"--width needs a value"});
  ExpectMentions(ParseError({"--height", "100", "--mode"}), {"--mode needs a value"});
  ExpectMentions(ParseError({"--scene"}), {"--scene needs a value"});
}

TEST(ConfigTest, NonNumbersAreRefused) {
  ExpectMentions(ParseError({"--width", "wide"}), {"--width expects a number", "'wide'"});
  ExpectMentions(ParseError({"--height", "100px"}), {"--height", "'100px'"});
  ExpectMentions(ParseError({"--physics-hz", ""}), {"--physics-hz expects a number"});
  ExpectMentions(ParseError({"--frame-hz", "nan"}), {"--frame-hz"});
  ExpectMentions(ParseError({"--frame-hz", "inf"}), {"--frame-hz"});
  ExpectMentions(ParseError({"--seed", "1.5"}), {"--seed", "'1.5'"});
  ExpectMentions(ParseError({"--tcp-port", "80 "}), {"--tcp-port"});
  ExpectMentions(ParseError({"--max-clients", "0x10"}), {"--max-clients"});
}

TEST(ConfigTest, OutOfRangeIsRefused) {
  ExpectMentions(ParseError({"--width", "15"}), {"--width is 15", "[16, 4096]"});
  ExpectMentions(ParseError({"--width", "4097"}), {"--width is 4097"});
  ExpectMentions(ParseError({"--height", "0"}), {"--height is 0"});
  ExpectMentions(ParseError({"--physics-hz", "0"}), {"--physics-hz is 0"});
  ExpectMentions(ParseError({"--physics-hz", "100001"}), {"--physics-hz is 100001"});
  ExpectMentions(ParseError({"--frame-hz", "0.05"}), {"--frame-hz is 0.05"});
  ExpectMentions(ParseError({"--frame-hz", "2000"}), {"--frame-hz is 2000"});
  ExpectMentions(ParseError({"--max-message-bytes", "15"}), {"--max-message-bytes is 15"});
  ExpectMentions(ParseError({"--max-message-bytes", "2000000000"}), {"--max-message-bytes"});
  ExpectMentions(ParseError({"--max-clients", "0"}), {"--max-clients is 0"});
  ExpectMentions(ParseError({"--tcp-port", "65536"}), {"--tcp-port", "65536"});
  ExpectMentions(ParseError({"--tcp-port", "99999999999"}), {"--tcp-port"});
  ExpectMentions(ParseError({"--udp-port", "-2"}), {"--udp-port is -2"});
  ExpectMentions(ParseError({"--udp-port", "65536"}), {"--udp-port is 65536"});
  ExpectMentions(ParseError({"--udp-datagram-bytes", "575"}), {"--udp-datagram-bytes is 575"});
  ExpectMentions(ParseError({"--udp-datagram-bytes", "65001"}), {"--udp-datagram-bytes is 65001"});
  ExpectMentions(ParseError({"--udp-expiry-ms", "9"}), {"--udp-expiry-ms is 9"});
  ExpectMentions(ParseError({"--shm-slots", "1"}), {"--shm-slots is 1"});
  ExpectMentions(ParseError({"--shm-slots", "1025"}), {"--shm-slots is 1025"});
}

TEST(ConfigTest, BadShmNamesAreRefused) {
  ExpectMentions(ParseError({"--shm-name", ""}), {"--shm-name", "without '/'"});
  ExpectMentions(ParseError({"--shm-name", "a/b"}), {"--shm-name 'a/b'"});
  ExpectMentions(ParseError({"--shm-name", "//x"}), {"--shm-name '//x'"});
  ExpectMentions(ParseError({"--shm-name", std::string(250, 'x')}), {"--shm-name"});
}

TEST(ConfigTest, ShmChannels) {
  EXPECT_EQ(Parse({"--shm-channels", "rgb,depth,mask"}).shm_channel_mask, 0x0eu);
  EXPECT_EQ(Parse({"--shm-channels", "mask,rgb"}).shm_channel_mask,
            (1u << proto::CHANNEL_RGB) | (1u << proto::CHANNEL_MASK));
  EXPECT_EQ(Parse({"--shm-channels", "depth"}).shm_channel_mask, 1u << proto::CHANNEL_DEPTH);
  // Each refusal names the flag, the value and what is wrong with it.
  ExpectMentions(ParseError({"--shm-channels", "rgb,boxes"}),
                 {"--shm-channels is 'rgb,boxes'", "'boxes' is not a channel",
                  "use rgb,depth,mask,semantic,normals,flow", "use " + channels::Names(channels::kAllPixels)});
  ExpectMentions(ParseError({"--shm-channels", "RGB"}), {"--shm-channels is 'RGB'", "'RGB' is not a channel"});
  ExpectMentions(ParseError({"--shm-channels", "rgb, depth"}), {"--shm-channels", "' depth' is not a channel"});
  ExpectMentions(ParseError({"--shm-channels", ""}), {"--shm-channels is ''", "'' is not a channel"});
  ExpectMentions(ParseError({"--shm-channels", "rgb,"}), {"--shm-channels is 'rgb,'", "'' is not a channel"});
  ExpectMentions(ParseError({"--shm-channels", "rgb,depth,rgb"}), {"--shm-channels is 'rgb,depth,rgb'", "rgb twice"});
}

// BUG: --shm-name (server/daemon/config.cpp) accepts "/" (non-empty, no '/'
// after the first character) and stores shm_name "/", a name with nothing
// after the slash that shm_open refuses (EINVAL) only later, at startup.
TEST(ConfigTest, BareSlashShmNameIsRefused) { ExpectMentions(ParseError({"--shm-name", "/"}), {"--shm-name"}); }

TEST(ConfigTest, NegativeNumbersAreRefused) {
  // These wrap (see below) to values beyond the range, so the range check
  // happens to catch them.
  ExpectMentions(ParseError({"--width", "-320"}), {"--width", "-320"});
  ExpectMentions(ParseError({"--max-clients", "-5"}), {"--max-clients", "-5"});
}

// BUG: ParseNumber<unsigned T> (server/daemon/config.cpp) reads "-N" with
// istream >> unsigned, which (like strtoul) negates modulo 2^bits without
// setting failbit; when the wrapped value lands inside [low, high] the flag is
// accepted: `--seed -1` becomes seed 18446744073709551615, `--tcp-port -1`
// becomes port 65535, `--max-message-bytes -4294967280` becomes 16.
TEST(ConfigTest, NegativeSeedIsRefused) { ExpectMentions(ParseError({"--seed", "-1"}), {"--seed", "-1"}); }

TEST(ConfigTest, NegativeTcpPortIsRefused) {
  // BUG: see NegativeSeedIsRefused; -1 wraps to 65535 in a uint16.
  ExpectMentions(ParseError({"--tcp-port", "-1"}), {"--tcp-port", "-1"});
}

TEST(ConfigTest, NegativeValueWrappingIntoRangeIsRefused) {
  // BUG: see NegativeSeedIsRefused; -4294967280 wraps to 16 in a uint32.
  ExpectMentions(ParseError({"--max-message-bytes", "-4294967280"}), {"--max-message-bytes"});
}

TEST(ConfigTest, BadModeAndLogLevelAreNamed) {
  ExpectMentions(ParseError({"--mode", "foo"}), {"--mode is 'foo'", "lockstep or realtime"});
  ExpectMentions(ParseError({"--mode", "Lockstep"}), {"--mode is 'Lockstep'"});
  ExpectMentions(ParseError({"--log-level", "verbose"}), {"--log-level is 'verbose'", "debug, info, warning or error"});
}

TEST(ConfigTest, PhysicsHzMustBeAMultipleOfFrameHz) {
  ExpectMentions(ParseError({"--physics-hz", "100", "--frame-hz", "30"}),
                 {"--physics-hz 100", "whole multiple", "--frame-hz 30"});
  ExpectMentions(ParseError({"--frame-hz", "31"}), {"--physics-hz 240", "--frame-hz 31"});
  // Slower physics than frames is no multiple either.
  ExpectMentions(ParseError({"--physics-hz", "10", "--frame-hz", "20"}), {"whole multiple"});
  // Order of the flags does not matter; the check runs after all of them.
  EXPECT_EQ(Parse({"--frame-hz", "50", "--physics-hz", "1000"}).substeps_per_frame(), 20u);
}

TEST(ConfigTest, SubstepsPerFrame) {
  Config config;
  EXPECT_EQ(config.substeps_per_frame(), 8u);
  config.physics_hz = 30;
  config.frame_hz = 30;
  EXPECT_EQ(config.substeps_per_frame(), 1u);
  config.physics_hz = 1000;
  config.frame_hz = 0.5;
  EXPECT_EQ(config.substeps_per_frame(), 2000u);
  EXPECT_EQ(Parse({"--physics-hz", "600", "--frame-hz", "60"}).substeps_per_frame(), 10u);
  EXPECT_EQ(Parse({"--physics-hz", "2.5", "--frame-hz", "0.5"}).substeps_per_frame(), 5u);
}

}  // namespace
}  // namespace sim4cv::daemon
