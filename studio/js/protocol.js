// One WebSocket to the daemon is one client session, exactly like a TCP
// connection (docs/protocol.md, "WebSocket"): text messages carry Envelopes
// as JSON with the .proto's field names; a Frame's text message is followed
// by one binary message holding its images' bytes. Answers are matched to
// requests here so the rest of the page awaits promises.

export const PROTOCOL_VERSION = 1;

// ws://host:port/ws?rgb=jpeg|raw&quality=N on the page's own host and port.
function socketUrl(options) {
  const query = new URLSearchParams();
  if (options.rgb) query.set("rgb", options.rgb);
  if (options.quality) query.set("quality", String(options.quality));
  const scheme = location.protocol === "https:" ? "wss:" : "ws:";
  return `${scheme}//${location.host}/ws?${query}`;
}

// An Error envelope as a JS exception (code, message, fatal, request_id).
export class DaemonError extends Error {
  constructor(error) {
    super(error.message || error.code || "error");
    this.code = error.code || "ERROR_CODE_UNSPECIFIED";
    this.fatal = Boolean(error.fatal);
    this.requestId = Number(error.request_id || 0);
  }
}

export class StudioSocket {
  // `options`: {rgb: "jpeg"|"raw", quality: 1..100}; the callbacks below may be set.
  constructor(clientName, options = {}) {
    this.clientName = clientName;
    this.url = socketUrl(options);
    this.welcome = null;
    this.onFrame = null;  // (frameHeader, ArrayBuffer) => void
    this.onError = null;  // (DaemonError) => void, for Errors no request awaits
    this.onClose = null;  // (reason string) => void
    this.nextRequestId = 1;
    this.configures = new Map();  // request_id -> {resolve, reject}
    this.stateWaiters = [];  // GetState answers come back in order
    this.subscribeWaiter = null;
    this.frameHeader = null;  // a Frame's text message, waiting for its binary one
    this.closed = false;
  }

  // Connects and says Hello; resolves with the Welcome.
  open() {
    return new Promise((resolve, reject) => {
      this.ws = new WebSocket(this.url);
      this.ws.binaryType = "arraybuffer";
      this.helloWaiter = { resolve, reject };
      // The daemon's access token (docs/security.md): the cookie the page's
      // ?token= URL set carries it; Hello carries it too, for a browser that
      // keeps no cookies.
      const token = new URLSearchParams(globalThis.location?.search ?? "").get("token");
      this.ws.onopen = () =>
        this.send({ hello: { protocol_version: PROTOCOL_VERSION, client_name: this.clientName, ...(token ? { token } : {}) } });
      this.ws.onmessage = (event) => this.dispatch(event.data);
      this.ws.onclose = (event) => this.closedBy(`WebSocket closed (${event.code}${event.reason ? ": " + event.reason : ""})`);
      this.ws.onerror = () => {};  // onclose follows with the code
    });
  }

  send(envelope) {
    if (this.ws && this.ws.readyState === WebSocket.OPEN) this.ws.send(JSON.stringify(envelope));
  }

  close() {
    this.closed = true;
    if (this.ws) this.ws.close();
  }

  // A Configure request ({load_map: {...}}, {get_world: {}}, ...); resolves
  // with Configured, rejects with the DaemonError that answers it.
  configure(request) {
    const requestId = this.nextRequestId++;
    return new Promise((resolve, reject) => {
      this.configures.set(requestId, { resolve, reject });
      this.send({ configure: { request_id: requestId, ...request } });
    });
  }

  // Driving commands for car `entityId` (steering -1..1, throttle and brake
  // 0..1). No answer when they are taken; a refusal (another client drives
  // the car: INVALID_STATE; not a car: UNKNOWN_ENTITY) comes to onError.
  sendControls(entityId, { steering = 0, throttle = 0, brake = 0 }) {
    this.send({ controls: { entity_id: entityId, steering, throttle, brake } });
  }

  getState() {
    return new Promise((resolve, reject) => {
      this.stateWaiters.push({ resolve, reject });
      this.send({ get_state: {} });
    });
  }

  // channels: e.g. ["CHANNEL_RGB", "CHANNEL_BOXES"]. A viewer is always
  // DELIVERY_NEWEST: it gets the newest frame and never holds lockstep back;
  // maxFps caps how often the daemon renders and sends for it (0: every frame).
  subscribe(camera, channels, maxFps = 30, withState = false) {
    return new Promise((resolve, reject) => {
      this.subscribeWaiter = { resolve, reject };
      this.send({ subscribe: { camera, channels, delivery: "DELIVERY_NEWEST", with_state: withState,
                               max_fps: maxFps } });
    });
  }

  dispatch(data) {
    if (typeof data !== "string") {
      const header = this.frameHeader;
      this.frameHeader = null;
      if (header && this.onFrame) this.onFrame(header, data);
      return;
    }
    const envelope = JSON.parse(data);
    if (envelope.frame) {
      this.frameHeader = envelope.frame;
    } else if (envelope.welcome) {
      this.welcome = envelope.welcome;
      this.helloWaiter?.resolve(envelope.welcome);
      this.helloWaiter = null;
    } else if (envelope.subscribed) {
      this.subscribeWaiter?.resolve(envelope.subscribed);
      this.subscribeWaiter = null;
    } else if (envelope.state) {
      this.stateWaiters.shift()?.resolve(envelope.state);
    } else if (envelope.configured) {
      const id = Number(envelope.configured.request_id || 0);
      this.configures.get(id)?.resolve(envelope.configured);
      this.configures.delete(id);
    } else if (envelope.error) {
      this.failed(new DaemonError(envelope.error));
    }
  }

  // An Error goes to the request it answers (a Configure by request_id; the
  // Hello or Subscribe awaited), else to onError.
  failed(error) {
    let waiter = null;
    if (error.requestId && this.configures.has(error.requestId)) {
      waiter = this.configures.get(error.requestId);
      this.configures.delete(error.requestId);
    } else if (this.helloWaiter) {
      waiter = this.helloWaiter;
      this.helloWaiter = null;
    } else if (this.subscribeWaiter) {
      waiter = this.subscribeWaiter;
      this.subscribeWaiter = null;
    }
    if (waiter) waiter.reject(error);
    if (this.onError && (!waiter || error.fatal)) this.onError(error);
  }

  closedBy(reason) {
    const error = new Error(reason);
    // Requests still open on a socket the page closed itself (a view switching to
    // lossless, or closed) are abandoned, not failed: nobody needs to hear of them.
    error.aborted = this.closed;
    this.helloWaiter?.reject(error);
    for (const waiter of this.configures.values()) waiter.reject(error);
    for (const waiter of this.stateWaiters) waiter.reject(error);
    this.subscribeWaiter?.reject(error);
    this.configures.clear();
    this.stateWaiters = [];
    this.subscribeWaiter = this.helloWaiter = null;
    if (!this.closed && this.onClose) this.onClose(reason);
    this.closed = true;
  }
}

// The daemon's CLOCK_MONOTONIC (Frame.render_end_mono_ns) in this page's
// performance.now() milliseconds: the offset from the fastest of a few
// round trips to /clock, good to half that round trip.
export async function estimateClockOffsetMs(tries = 5) {
  let best = null;
  for (let i = 0; i < tries; ++i) {
    const before = performance.now();
    const text = await (await fetch("/clock", { cache: "no-store" })).text();
    const after = performance.now();
    const daemonMs = Number(BigInt(text) / 1000n) / 1000;
    if (!best || after - before < best.roundTrip) {
      best = { roundTrip: after - before, offset: daemonMs - (before + after) / 2 };
    }
  }
  return best.offset;
}
