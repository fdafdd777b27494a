// A live view: its own WebSocket (one client session per view), subscribed
// DELIVERY_NEWEST to one camera's channel, so the daemon's mailbox keeps only
// the newest frame for it and a slow page never holds the simulation back.
// Here too only the newest frame is drawn: one arriving while the last is
// still decoding replaces the one waiting.

import { StudioSocket } from "./protocol.js";
import { CHANNELS, CLASS_COLOURS, className, toRgba } from "./colours.js";
import { option, setOptions } from "./dom.js";

export class LiveView {
  // app: {cameras(), clockOffsetMs, reportError(error)}; index: for ids;
  // options: {boxes: false} starts without drawing the boxes (a view to drive by).
  constructor(app, parent, index, camera, channel = "CHANNEL_RGB", options = {}) {
    this.app = app;
    this.index = index;
    this.camera = camera;
    this.channel = channel;
    this.boxes = options.boxes ?? true;
    this.rgb = "jpeg";
    this.maxFps = app.maxFps ?? 30;
    this.frames = 0;
    this.bytes = 0;  // binary bytes of the frames drawn
    this.drawMs = 0;  // time spent decoding and drawing them
    this.lastHeader = null;
    this.waiting = null;  // the newest frame not yet drawn
    this.drawing = false;
    this.fps = 0;
    this.latencyMs = null;
    this.frameTimes = [];
    this.build(parent);
  }

  build(parent) {
    const panel = document.createElement("section");
    panel.className = "view";
    panel.id = `view-${this.index}`;
    panel.innerHTML = `
      <div class="view-bar">
        <select class="camera" title="camera"></select>
        <select class="channel" title="channel"></select>
        <label title="ground-truth boxes and ids"><input type="checkbox" class="boxes" checked> boxes</label>
        <select class="rgb" title="how RGB travels: JPEG (a tenth of the bytes) or lossless">
          <option value="jpeg">JPEG</option><option value="raw">lossless</option></select>
        <select class="fps" title="at most this many frames a second (the daemon renders for this view only that often)">
          <option value="10">10 fps</option><option value="30">30 fps</option><option value="60">60 fps</option>
          <option value="0">every frame</option></select>
        <button class="remove" title="close this view">×</button>
      </div>
      <div class="view-canvas"><canvas class="image"></canvas><canvas class="overlay"></canvas></div>
      <div class="view-stats">connecting…</div>`;
    parent.appendChild(panel);
    this.panel = panel;
    this.image = panel.querySelector("canvas.image");
    this.overlay = panel.querySelector("canvas.overlay");
    this.stats = panel.querySelector(".view-stats");
    const channel = panel.querySelector("select.channel");
    setOptions(channel, CHANNELS.map((c) => option(c.label, c.channel)));
    channel.value = this.channel;
    channel.onchange = () => { this.channel = channel.value; this.subscribe(); };
    panel.querySelector("input.boxes").checked = this.boxes;
    panel.querySelector("input.boxes").onchange = (e) => { this.boxes = e.target.checked; };
    const rgb = panel.querySelector("select.rgb");
    rgb.onchange = () => { this.rgb = rgb.value; this.reconnect(); };
    const fps = panel.querySelector("select.fps");
    fps.value = String(this.maxFps);
    fps.onchange = () => { this.maxFps = Number(fps.value); this.subscribe(); };
    panel.querySelector("select.camera").onchange = (e) => { this.camera = e.target.value; this.subscribe(); };
    panel.querySelector("button.remove").onclick = () => this.app.removeView(this);
    this.updateCameras();
  }

  updateCameras() {
    const select = this.panel.querySelector("select.camera");
    const names = this.app.cameras();
    setOptions(select, names.map((n) => option(n)), false);
    if (!names.includes(this.camera) && names.length) this.camera = names[0];
    select.value = this.camera;
  }

  async connect() {
    this.socket = new StudioSocket(`studio-view-${this.index}`, { rgb: this.rgb });
    this.socket.onFrame = (header, bytes) => this.received(header, bytes);
    this.socket.onError = (error) => this.app.reportError(error, `view ${this.index + 1}`);
    this.socket.onClose = (reason) => { this.stats.textContent = reason; };
    try {
      await this.socket.open();
      await this.subscribe();
    } catch (error) {
      this.app.reportError(error, `view ${this.index + 1}`);
    }
  }

  reconnect() {
    this.socket?.close();
    this.connect();
  }

  async subscribe() {
    if (!this.socket || !this.camera) return;
    // The boxes' channel also brings the camera's pose and intrinsics, which a
    // view to drive by or the editor's preview uses without drawing the boxes.
    const channels = [this.channel, "CHANNEL_BOXES"];
    this.frames = 0;
    this.frameTimes = [];
    try {
      await this.socket.subscribe(this.camera, channels, this.maxFps);
      this.stats.textContent = `subscribed to ${this.camera}, waiting for a frame…`;
    } catch (error) {
      this.app.reportError(error, `view ${this.index + 1}`);
    }
  }

  close() {
    this.socket?.close();
    this.panel.remove();
  }

  received(header, bytes) {
    this.waiting = { header, bytes, arrivedMs: performance.now() };
    if (!this.drawing) this.drawNext();
  }

  async drawNext() {
    this.drawing = true;
    while (this.waiting) {
      const { header, bytes } = this.waiting;
      this.waiting = null;
      try {
        await this.draw(header, bytes);
      } catch (error) {
        this.app.reportError(error, `view ${this.index + 1}`);
      }
    }
    this.drawing = false;
  }

  async draw(header, buffer) {
    const started = performance.now();
    const width = header.width, height = header.height;
    let offset = 0, shown = null;
    for (const image of header.images || []) {
      const size = image.binary_bytes || 0;
      if (image.channel === this.channel) shown = { image, bytes: new Uint8Array(buffer, offset, size) };
      offset += size;
    }
    if (!shown) return;
    for (const canvas of [this.image, this.overlay]) {
      if (canvas.width !== width || canvas.height !== height) { canvas.width = width; canvas.height = height; }
    }
    const context = this.image.getContext("2d");
    if (shown.image.encoding === "IMAGE_ENCODING_JPEG") {
      const bitmap = await createImageBitmap(new Blob([shown.bytes], { type: "image/jpeg" }));
      context.drawImage(bitmap, 0, 0);
      bitmap.close();
    } else {
      const pixels = context.createImageData(width, height);
      toRgba(shown.image.channel, shown.bytes, pixels.data);
      context.putImageData(pixels, 0, 0);
    }
    this.drawBoxes(header);
    this.lastHeader = header;
    this.frames += 1;
    this.bytes += buffer.byteLength;
    this.drawMs += performance.now() - started;
    this.measure(header);
  }

  drawBoxes(header) {
    const context = this.overlay.getContext("2d");
    context.clearRect(0, 0, this.overlay.width, this.overlay.height);
    if (!this.boxes) return;
    context.font = "10px sans-serif";
    context.lineWidth = 1.5;
    for (const box of header.boxes || []) {
      const colour = CLASS_COLOURS[box.object_class] || "#ffffff";
      context.strokeStyle = colour;
      context.strokeRect((box.x || 0) + 0.5, (box.y || 0) + 0.5, box.width || 0, box.height || 0);
      const label = `${box.object_id} ${className(box.object_class)}`;
      const textY = (box.y || 0) > 12 ? (box.y || 0) - 3 : (box.y || 0) + 11;
      context.fillStyle = "rgba(0,0,0,0.6)";
      context.fillRect(box.x || 0, textY - 9, context.measureText(label).width + 4, 11);
      context.fillStyle = colour;
      context.fillText(label, (box.x || 0) + 2, textY);
    }
  }

  // Frame rate over the last second; latency from the end of rendering to
  // now, on the daemon's clock (the offset estimated through /clock).
  measure(header) {
    const now = performance.now();
    this.frameTimes.push(now);
    while (this.frameTimes.length && this.frameTimes[0] < now - 1000) this.frameTimes.shift();
    this.fps = this.frameTimes.length > 1 ? (this.frameTimes.length - 1) * 1000 / (now - this.frameTimes[0]) : 0;
    const rendered = header.render_end_mono_ns ? Number(BigInt(header.render_end_mono_ns) / 1000n) / 1000 : null;
    this.latencyMs = rendered !== null && this.app.clockOffsetMs !== null ? now + this.app.clockOffsetMs - rendered : null;
    const latency = this.latencyMs === null ? "?" : this.latencyMs.toFixed(1);
    this.stats.textContent = `${header.camera} · frame ${header.frame_id} · ${this.fps.toFixed(1)} fps · ` +
      `latency ${latency} ms · dropped ${header.dropped_frames || 0} · ${(header.boxes || []).length} boxes`;
  }
}
