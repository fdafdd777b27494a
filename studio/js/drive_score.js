// The score of a person driving from the page: the driving case study's
// deviation metric (docs/driving.md, "Closed-loop evaluation";
// clients/python/sim4cv/driving_metrics.py), from the daemon's own road graph.
//
// Every sample is the car's state (sim time, position, heading, speed) and
// QueryRoad's answer for its position and heading (use_heading: only lanes
// running within 90 degrees of the car's heading count): |lateral_offset| is
// the distance from the right-lane centre in the direction of travel. Samples
// come as fast as the page gets them (not at a fixed step), so every number
// is weighted by simulated time: a sample's deviation holds until the next
// sample (at most MAX_GAP_S, so a page that was in the background does not
// give one sample minutes of weight). A lane departure is an entry into
// |deviation| > 1 m (the 2 m car's side leaves the 4 m lane).

export const LANE_DEPARTURE_M = 1.0;
export const WITHIN_M = [0.25, 0.5, 1.0];
export const MAX_GAP_S = 1.0;

// What to compare with (docs/driving.md, "Results"; the paper: Sim4CV, IJCV 2018).
export const REFERENCES = [
  { name: "paper: best human driver", mean_deviation_cm: 30.17 },
  { name: "paper: network, random views", mean_deviation_cm: 7.12, within_25cm: 0.955, within_50cm: 0.9966,
    within_1m: 1.0 },
  { name: "paper: network, fixed views", mean_deviation_cm: 14.61, within_25cm: 0.8944, within_50cm: 0.968,
    within_1m: 0.9954 },
  { name: "shipped model (its model card: waypoint 2, gain 0.9, turn slowdown 0.5, bend correction 0.2)",
    mean_deviation_cm: 6.48, within_25cm: 0.962, within_50cm: 0.9981, within_1m: 1.0 },
];

export class DriveScore {
  constructor(info = {}) {
    this.info = info;  // car, map, camera, start time: written into the run's log
    this.samples = [];  // {t, x, y, yaw_deg, speed, deviation_m (+ right of travel), steering, throttle, brake}
    this.time_s = 0;  // simulated seconds the score covers
    this.weighted_m = 0;  // ∫ |deviation| dt
    this.within_s = WITHIN_M.map(() => 0);
    this.max_m = 0;
    this.departures = 0;
    this.beyond = false;
    this.distance_m = 0;
    this.last = null;
  }

  // One sample; `deviation` is null where the daemon had no answer (no road
  // graph): the sample still counts for the distance, not for the deviation.
  add(sample) {
    const last = this.last;
    this.samples.push(sample);
    this.last = sample;
    if (last) {
      const dt = sample.t - last.t;
      if (dt > 0) {
        const step = Math.hypot(sample.x - last.x, sample.y - last.y);
        if (step <= 60 * dt + 1) this.distance_m += step;  // not a jump (a Reset, a respawn)
        if (last.deviation_m !== null) {
          const weight = Math.min(dt, MAX_GAP_S), d = Math.abs(last.deviation_m);
          this.time_s += weight;
          this.weighted_m += weight * d;
          WITHIN_M.forEach((w, i) => { if (d <= w) this.within_s[i] += weight; });
        }
      }
    }
    if (sample.deviation_m !== null) {
      const d = Math.abs(sample.deviation_m);
      this.max_m = Math.max(this.max_m, d);
      const beyond = d > LANE_DEPARTURE_M;
      if (beyond && !this.beyond) this.departures += 1;
      this.beyond = beyond;
    }
  }

  // The numbers, named as driving_metrics.score names them (null before
  // two samples with a deviation).
  summary() {
    const t = this.time_s;
    const fraction = (i) => (t > 0 ? this.within_s[i] / t : null);
    return {
      samples: this.samples.length,
      seconds: t,
      mean_deviation_cm: t > 0 ? (100 * this.weighted_m) / t : null,
      max_deviation_cm: this.samples.some((s) => s.deviation_m !== null) ? 100 * this.max_m : null,
      within_25cm: fraction(0),
      within_50cm: fraction(1),
      within_1m: fraction(2),
      lane_departures: this.departures,
      distance_m: this.distance_m,
      current_deviation_m: this.last ? this.last.deviation_m : null,
    };
  }

  // The run as a JSON document: what was driven, the score, every sample.
  toJSON() {
    return {
      format: "sim4cv-studio-drive-run 1",
      metric: "deviation = -QueryRoad.lateral_offset (m, + right of the direction of travel) from the " +
              "right-lane centre of the nearest lane running within 90 degrees of the car's heading; " +
              "time-weighted (each sample holds until the next, at most " + MAX_GAP_S + " s)",
      ...this.info,
      score: this.summary(),
      references: REFERENCES,
      columns: ["t", "x", "y", "yaw_deg", "speed", "deviation_m", "steering", "throttle", "brake"],
      samples: this.samples.map((s) => [s.t, s.x, s.y, s.yaw_deg, s.speed, s.deviation_m, s.steering, s.throttle,
                                        s.brake]),
    };
  }
}

// A table of the live score beside the references, as HTML rows.
export function scoreRows(summary) {
  const percent = (v) => (v === null || v === undefined ? "–" : `${(100 * v).toFixed(1)}%`);
  const cm = (v) => (v === null || v === undefined ? "–" : `${v.toFixed(2)}`);
  const row = (name, s, cls = "") =>
    `<tr class="${cls}"><td>${name}</td><td>${cm(s.mean_deviation_cm)}</td><td>${percent(s.within_25cm)}</td>` +
    `<td>${percent(s.within_50cm)}</td><td>${percent(s.within_1m)}</td></tr>`;
  return `<tr><th></th><th title="time-weighted mean |deviation|">mean cm</th><th>≤25 cm</th><th>≤50 cm</th>` +
    `<th>≤1 m</th></tr>` + row("you", summary, "you") + REFERENCES.map((r) => row(r.name, r)).join("");
}

// The rest of the score in a line: where the car is now, the worst, departures, distance, time.
export function scoreTotals(s) {
  const now = s.current_deviation_m;
  const side = now === null ? "–" : `${Math.abs(100 * now).toFixed(0)} cm ${now > 0 ? "right" : "left"}`;
  const max = s.max_deviation_cm === null ? "–" : `${s.max_deviation_cm.toFixed(0)} cm`;
  return `now ${side} · max ${max} · departures ${s.lane_departures} · ${s.distance_m.toFixed(1)} m ` +
    `in ${s.seconds.toFixed(1)} s · ${s.samples} samples`;
}
