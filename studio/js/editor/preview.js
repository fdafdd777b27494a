// The 3D preview: Play the map, then a camera fixed in the world (AddCamera
// without mounted_on) above a corner of the map looking at its centre,
// shown in a live view (live_view.js: its own WebSocket session). The
// buttons, or a drag on the image, orbit it around the map (SetCameraPose).

import { LiveView } from "../live_view.js";
import { estimateClockOffsetMs } from "../protocol.js";

export const PREVIEW_CAMERA = "preview";
const WIDTH = 480, HEIGHT = 270, FOV_Y_DEG = 60, MAX_FPS = 10;  // 10: one of the view's own fps choices
const $ = (id) => document.getElementById(id);
const DEG = Math.PI / 180;

export class Preview {
  constructor(app) {
    this.app = app;
    this.view = null;
    this.orbit = null;  // {azimuthDeg, distance, height}: where the camera is, about the map's centre
    this.sending = false;
    this.pending = false;
    this.clockOffsetMs = null;
    $("preview").onclick = () => this.start();
    const turn = (f) => () => { if (this.orbit) { f(this.orbit); this.sendPose(); } };
    $("orbit-left").onclick = turn((o) => { o.azimuthDeg -= 15; });
    $("orbit-right").onclick = turn((o) => { o.azimuthDeg += 15; });
    $("orbit-up").onclick = turn((o) => { o.height = Math.min(o.height * 1.25, 900); });
    $("orbit-down").onclick = turn((o) => { o.height = Math.max(o.height / 1.25, 2); });
    $("orbit-in").onclick = turn((o) => { o.distance = Math.max(o.distance / 1.25, 5); });
    $("orbit-out").onclick = turn((o) => { o.distance = Math.min(o.distance * 1.25, 900); });
    this.enableOrbit(false);
  }

  enableOrbit(on) {
    for (const id of ["orbit-left", "orbit-right", "orbit-up", "orbit-down", "orbit-in", "orbit-out"]) $(id).disabled = !on;
  }

  // The pose of the camera for the current orbit: yaw toward the centre,
  // pitched down to look at it.
  pose() {
    const o = this.orbit, a = o.azimuthDeg * DEG;
    let yaw = o.azimuthDeg + 180;
    yaw = ((yaw + 180) % 360 + 360) % 360 - 180;
    return {
      position: { x: o.distance * Math.cos(a), y: o.distance * Math.sin(a), z: o.height },
      yaw_deg: yaw,
      pitch_down_deg: Math.atan2(o.height, o.distance) / DEG,
    };
  }

  async start() {
    if (!(await this.app.actions.play())) return false;
    const m = this.app.model;
    const cx = (-m.width * m.tileSize) / 2, cy = (-m.height * m.tileSize) / 2;  // the south-west corner
    const distance = Math.hypot(cx, cy);
    this.orbit = { azimuthDeg: Math.atan2(cy, cx) / DEG, distance, height: Math.max(15, distance * 0.6) };
    const pose = this.pose();
    try {
      await this.app.configure({ add_camera: {
        name: PREVIEW_CAMERA, width: WIDTH, height: HEIGHT, fov_y_deg: FOV_Y_DEG,
        pitch_down_deg: pose.pitch_down_deg, yaw_deg: pose.yaw_deg, gimbal: false, offset: pose.position } });
    } catch (error) {
      this.app.reportError(error, "3D preview");
      return false;
    }
    if (this.clockOffsetMs === null) this.clockOffsetMs = await estimateClockOffsetMs().catch(() => null);
    this.openView();
    this.enableOrbit(true);
    const lockstep = this.app.socket.welcome?.mode === "SIM_MODE_LOCKSTEP";
    this.app.note(`3D preview of ${m.name}: drag the image or use the buttons to orbit` +
                  (lockstep ? " (a lockstep daemon makes frames only while its lockstep client steps)" : ""));
    return true;
  }

  openView() {
    const owner = {
      maxFps: MAX_FPS,
      clockOffsetMs: this.clockOffsetMs,
      cameras: () => [PREVIEW_CAMERA],
      reportError: (error, where) => this.app.reportError(error, where),
      removeView: () => this.stopView(),
    };
    this.view = new LiveView(owner, $("preview-box"), 0, PREVIEW_CAMERA, "CHANNEL_RGB", { boxes: false });
    this.dragToOrbit(this.view.overlay);
    this.view.connect();
  }

  dragToOrbit(element) {
    let last = null;
    element.style.cursor = "grab";
    element.addEventListener("pointerdown", (e) => {
      last = { x: e.clientX, y: e.clientY };
      element.setPointerCapture(e.pointerId);
    });
    element.addEventListener("pointermove", (e) => {
      if (!last || !this.orbit) return;
      this.orbit.azimuthDeg -= (e.clientX - last.x) * 0.4;
      this.orbit.height = Math.min(900, Math.max(2, this.orbit.height * Math.exp((e.clientY - last.y) * 0.01)));
      last = { x: e.clientX, y: e.clientY };
      this.sendPose();
    });
    const up = () => { last = null; };
    element.addEventListener("pointerup", up);
    element.addEventListener("pointercancel", up);
  }

  // SetCameraPose, one at a time: poses asked for while one is on its way
  // collapse into the newest.
  async sendPose() {
    if (this.sending) { this.pending = true; return; }
    this.sending = true;
    try {
      do {
        this.pending = false;
        const pose = this.pose();
        await this.app.configure({ set_camera_pose: { camera: PREVIEW_CAMERA, ...pose } });
      } while (this.pending);
    } catch (error) {
      this.app.reportError(error, "orbit");
    } finally {
      this.sending = false;
    }
  }

  stopView() {
    this.view?.close();
    this.view = null;
    this.enableOrbit(false);
  }
}
