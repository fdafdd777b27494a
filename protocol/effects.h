// The camera effects, listed once: what a real camera does to the RGB after
// the light reaches it (docs/protocol.md, "Camera effects"). The daemon's
// flags (--antialias, --lens-k1, ...), Configure.set_effects, WorldInfo's
// effects, the renderer's effects pass (server/render/effects_pass.cpp) and
// the docs read this table. All are off by default: frames are then exactly
// what they were without them.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace sim4cv::effects {

// X(field, flag, default (off), min, max, whole numbers only, unit, what it
// does): field is also the name of the proto field in CameraEffects (sim4cv.proto).
#define SIM4CV_CAMERA_EFFECTS(X)                                                                                    \
  X(antialias, "antialias", 0, 0, 1, true, "", "edge smoothing of the RGB in a post pass (FXAA); 0 off, 1 on")      \
  X(exposure_ev, "exposure-ev", 0, -4, 4, false, "EV",                                                              \
    "exposure compensation: linear light times 2^EV, so bright parts clip")                                         \
  X(white_balance_k, "white-balance", 6500, 2000, 12000, false, "K",                                                \
    "the light colour the camera balances for; 6500 leaves the colours, lower turns the image blue, higher orange") \
  X(motion_blur, "motion-blur", 0, 0, 1, false, "frames",                                                           \
    "shutter time as a fraction of the frame period: the RGB is smeared along each pixel's motion, centred on the " \
    "rendered instant")                                                                                             \
  X(k1, "lens-k1", 0, -1, 1, false, "", "radial distortion, r^2 term (OpenCV's radial-tangential model)")           \
  X(k2, "lens-k2", 0, -1, 1, false, "", "radial distortion, r^4 term")                                              \
  X(p1, "lens-p1", 0, -0.1, 0.1, false, "", "tangential distortion p1")                                             \
  X(p2, "lens-p2", 0, -0.1, 0.1, false, "", "tangential distortion p2")                                             \
  X(k3, "lens-k3", 0, -1, 1, false, "", "radial distortion, r^6 term")                                              \
  X(jpeg_quality, "jpeg", 0, 0, 100, true, "",                                                                      \
    "JPEG compression of the RGB at this quality (1 worst .. 100 best); 0 off")

struct CameraEffects {
#define SIM4CV_EFFECT_FIELD(FIELD, FLAG, OFF, ...) double FIELD = OFF;
  SIM4CV_CAMERA_EFFECTS(SIM4CV_EFFECT_FIELD)
#undef SIM4CV_EFFECT_FIELD

  bool operator==(const CameraEffects&) const = default;
};

struct EffectInfo {
  std::string_view field;  // in CameraEffects, the proto and Python
  std::string_view flag;   // the daemon's --flag
  double off, min, max;
  bool whole;  // whole numbers only (a switch, a quality)
  std::string_view unit, summary;
  double CameraEffects::*member;
};

#define SIM4CV_EFFECT_INFO(FIELD, FLAG, OFF, MIN, MAX, WHOLE, UNIT, SUMMARY) \
  EffectInfo{#FIELD, FLAG, OFF, MIN, MAX, WHOLE, UNIT, SUMMARY, &CameraEffects::FIELD},
inline const std::array kEffects = {SIM4CV_CAMERA_EFFECTS(SIM4CV_EFFECT_INFO)};
#undef SIM4CV_EFFECT_INFO

// The effects with one of them on: Only(&CameraEffects::motion_blur, 1).
inline CameraEffects Only(double CameraEffects::*member, double value) {
  CameraEffects e;
  e.*member = value;
  return e;
}

// A wide-angle action camera's barrel lens with a little decentring: the
// lens the gallery, the render benchmark and the tests show.
inline CameraEffects WideAngleLens() {
  CameraEffects lens;
  lens.k1 = -0.28;
  lens.k2 = 0.07;
  lens.p1 = 0.002;
  lens.p2 = -0.0015;
  lens.k3 = -0.005;
  return lens;
}

// A barrel lens (negative k1) stops spreading the image at some radius
// and then folds it back: OpenCV's model means nothing past there. A lens
// must keep spreading at least until the distorted image reaches this radius
// (tan of the angle off axis: 0.5 is 27 degrees); pixels of a wider camera
// that lie past its fold are black and hold no ground truth.
inline constexpr double kLensCheckRadius = 0.5;

// The radial factor 1 + k1 r^2 + k2 r^4 + k3 r^6 at r^2 = `r2`.
inline double Radial(const CameraEffects& e, double r2) { return 1 + r2 * (e.k1 + r2 * (e.k2 + r2 * e.k3)); }

// The undistorted radius where the radial map r -> r Radial(r^2) folds (its
// derivative 1 + 3 k1 r^2 + 5 k2 r^4 + 7 k3 r^6 reaches 0), or 1e9 if it
// does not before r = 10.
inline double FoldRadius(const CameraEffects& e) {
  for (int i = 1; i <= 10000; ++i) {
    const double r = i * 1e-3, r2 = r * r;
    if (1 + r2 * (3 * e.k1 + r2 * (5 * e.k2 + r2 * 7 * e.k3)) <= 0) return r;
  }
  return 1e9;
}

inline bool Distorts(const CameraEffects& e) { return e.k1 != 0 || e.k2 != 0 || e.p1 != 0 || e.p2 != 0 || e.k3 != 0; }
inline bool Any(const CameraEffects& e) { return !(e == CameraEffects{}); }
// Effects applied by the GL effects pass (all but JPEG, done on the CPU).
inline bool NeedsPass(const CameraEffects& e) {
  CameraEffects gl = e;
  gl.jpeg_quality = 0;
  return Any(gl);
}

// OpenCV's model on normalised image coordinates (x = X/Z, y = Y/Z).
inline void Distort(const CameraEffects& e, double x, double y, double& xd, double& yd) {
  const double r2 = x * x + y * y;
  const double radial = Radial(e, r2);
  xd = x * radial + 2 * e.p1 * x * y + e.p2 * (r2 + 2 * x * x);
  yd = y * radial + e.p1 * (r2 + 2 * y * y) + 2 * e.p2 * x * y;
}

// The undistorted point that Distort maps onto (xd, yd): Newton's method
// from (xd, yd). False if it does not converge to 1e-9; a point past the
// lens's fold (FoldRadius) is a root the model does not mean: check it.
inline bool Undistort(const CameraEffects& e, double xd, double yd, double& x, double& y) {
  x = xd;
  y = yd;
  for (int i = 0; i < 50; ++i) {
    double fx = 0, fy = 0;
    Distort(e, x, y, fx, fy);
    const double ex = fx - xd, ey = fy - yd;
    if (std::abs(ex) < 1e-12 && std::abs(ey) < 1e-12) return true;
    // The Jacobian by central differences: the model is a smooth polynomial.
    const double h = 1e-7;
    double ax = 0, ay = 0, bx = 0, by = 0;
    Distort(e, x + h, y, ax, ay);
    double cx = 0, cy = 0;
    Distort(e, x - h, y, cx, cy);
    const double j00 = (ax - cx) / (2 * h), j10 = (ay - cy) / (2 * h);
    Distort(e, x, y + h, bx, by);
    Distort(e, x, y - h, cx, cy);
    const double j01 = (bx - cx) / (2 * h), j11 = (by - cy) / (2 * h);
    const double det = j00 * j11 - j01 * j10;
    if (!(std::abs(det) > 1e-12)) return false;
    x -= (j11 * ex - j01 * ey) / det;
    y -= (-j10 * ex + j00 * ey) / det;
  }
  double fx = 0, fy = 0;
  Distort(e, x, y, fx, fy);
  return std::abs(fx - xd) < 1e-9 && std::abs(fy - yd) < 1e-9;
}

// Empty if every field is in its range (and whole where it must be);
// otherwise a message naming the value and what is allowed. `flags`: name
// fields by their flag (--motion-blur), else as SetEffects.motion_blur.
inline std::string CheckRanges(const CameraEffects& e, bool flags) {
  std::ostringstream message;
  for (const EffectInfo& info : kEffects) {
    const double value = e.*info.member;
    const std::string name = flags ? "--" + std::string(info.flag) : "SetEffects." + std::string(info.field);
    if (!(value >= info.min && value <= info.max)) {
      message << name << " " << value << " is outside " << info.min << ".." << info.max;
      if (!info.unit.empty()) message << " " << info.unit;
      return message.str();
    }
    if (info.whole && value != std::floor(value)) {
      message << name << " " << value << " is not a whole number";
      return message.str();
    }
  }
  return {};
}

// Empty unless the lens folds the image before kLensCheckRadius; then a
// message naming the coefficients. Only a whole lens can be judged: a
// coefficient that folds alone may be balanced by another.
inline std::string CheckLens(const CameraEffects& e) {
  const double fold = FoldRadius(e);
  const double reached = fold * Radial(e, fold * fold);
  if (fold < 1e9 && reached < kLensCheckRadius) {
    std::ostringstream message;
    message << "the lens k1=" << e.k1 << " k2=" << e.k2 << " k3=" << e.k3 << " folds the image at radius " << reached
            << " (tan of the angle off axis; it must reach " << kLensCheckRadius << "): use smaller coefficients";
    return message.str();
  }
  return {};
}

// CheckRanges, then CheckLens: the effects a camera will use.
inline std::string Check(const CameraEffects& e, bool flags) {
  std::string problem = CheckRanges(e, flags);
  return problem.empty() ? CheckLens(e) : problem;
}

// "antialias 1, motion_blur 0.5" (the effects that are on), or "none".
inline std::string Describe(const CameraEffects& e) {
  std::ostringstream text;
  for (const EffectInfo& info : kEffects) {
    if (e.*info.member == info.off) continue;
    if (text.tellp() > 0) text << ", ";
    text << info.field << " " << e.*info.member;
  }
  return text.tellp() > 0 ? text.str() : "none";
}

}  // namespace sim4cv::effects
