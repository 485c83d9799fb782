// The clip's pose at any time: a line-for-line port of systems/animation/evaluate.cpp (tracks applied in
// order from the rest points, step / linear / smooth (Catmull-Rom Hermite) interpolation, easing, loop /
// once / ping-pong, twist angles reduced modulo 360 in degrees with exact quarter turns). Doubles
// throughout, as the engine's CPU evaluation.
"use strict";
(function () {
  function applyEasing(easing, u) {
    switch (easing) {
      case "ease_in": return u * u;
      case "ease_out": return 1 - (1 - u) * (1 - u);
      case "ease_in_out": return u * u * (3 - 2 * u);
      default: return u;
    }
  }

  function keyValue(track, key) {
    return track.kind === "twist" ? [key.angle, 0, 0] : key.value;
  }

  // Catmull-Rom tangent at key i (value per second); zero at the end keys.
  function tangent(track, i) {
    const keys = track.keys;
    if (i === 0 || i + 1 >= keys.length) return [0, 0, 0];
    const a = keyValue(track, keys[i - 1]), b = keyValue(track, keys[i + 1]);
    const dt = keys[i + 1].time - keys[i - 1].time;
    return [(b[0] - a[0]) / dt, (b[1] - a[1]) / dt, (b[2] - a[2]) / dt];
  }

  function evaluateTrack(track, t) {
    const keys = track.keys;
    if (keys.length === 0) return [0, 0, 0];
    if (!(t > keys[0].time)) return keyValue(track, keys[0]).slice();
    if (t >= keys[keys.length - 1].time) return keyValue(track, keys[keys.length - 1]).slice();
    let b = 1;
    while (b < keys.length && !(t < keys[b].time)) ++b;  // first key with time > t
    const a = b - 1, ka = keys[a], kb = keys[b];
    const va = keyValue(track, ka), vb = keyValue(track, kb);
    const span = kb.time - ka.time;
    const u = applyEasing(ka.easing || "none", (t - ka.time) / span);
    switch (ka.interpolation || "smooth") {
      case "step": return va.slice();
      case "linear": return [0, 1, 2].map((c) => va[c] + (vb[c] - va[c]) * u);
      default: {
        const u2 = u * u, u3 = u2 * u;
        const h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
        const ma = tangent(track, a), mb = tangent(track, b);
        return [0, 1, 2].map((c) => h00 * va[c] + h10 * span * ma[c] + h01 * vb[c] + h11 * span * mb[c]);
      }
    }
  }

  // C fmod: the remainder with the dividend's sign (JavaScript's % is the same for doubles).
  function mapClipTime(clip, raw) {
    const d = clip.duration;
    if (!(d > 0) || !Number.isFinite(raw)) return 0;
    switch (clip.mode || "loop") {
      case "once": return Math.min(Math.max(raw, 0), d);
      case "ping_pong": {
        const period = 2 * d;
        let r = raw % period;
        if (r < 0) r += period;
        if (r >= period) r = 0;
        return r > d ? period - r : r;
      }
      default: {
        let r = raw % d;
        if (r < 0) r += d;
        return r >= d ? 0 : r;
      }
    }
  }

  function makeTwist(pivot, axis, degrees) {
    let r = degrees % 360;
    if (r < 0) r += 360;
    const len = Math.hypot(axis[0], axis[1], axis[2]);
    if (r >= 360 || r === 0 || !Number.isFinite(r) || !(len > 0)) return null;
    let c, s;
    if (r === 90) { c = 0; s = 1; }
    else if (r === 180) { c = -1; s = 0; }
    else if (r === 270) { c = 0; s = -1; }
    else { const rad = r * (Math.PI / 180); c = Math.cos(rad); s = Math.sin(rad); }
    return { pivot, k: [axis[0] / len, axis[1] / len, axis[2] / len], c, s };
  }

  // Rodrigues' rotation formula about the pivot.
  function applyTwist(tw, p) {
    const d = [p[0] - tw.pivot[0], p[1] - tw.pivot[1], p[2] - tw.pivot[2]], k = tw.k;
    const cr = [k[1] * d[2] - k[2] * d[1], k[2] * d[0] - k[0] * d[2], k[0] * d[1] - k[1] * d[0]];
    const kd = (k[0] * d[0] + k[1] * d[1] + k[2] * d[2]) * (1 - tw.c);
    return [0, 1, 2].map((i) => tw.pivot[i] + d[i] * tw.c + cr[i] * tw.s + k[i] * kd);
  }

  function trackPivot(track, rest) {
    if (track.pivot) return track.pivot;
    const sum = [0, 0, 0];
    let n = 0;
    for (const idx of track.points) {
      if (idx >= rest.length) continue;
      for (let c = 0; c < 3; ++c) sum[c] += rest[idx][c];
      ++n;
    }
    return n ? sum.map((v) => v / n) : sum;
  }

  // The control points at clip time t: rest, then every track in order.
  function evaluatePose(clip, rest, t) {
    const out = rest.map((p) => p.slice());
    for (const track of clip.tracks || []) {
      if (!track.points || track.points.length === 0 || !track.keys || track.keys.length === 0) continue;
      const value = evaluateTrack(track, t);
      if (track.kind === "twist") {
        const tw = makeTwist(trackPivot(track, rest), track.axis, value[0]);
        if (!tw) continue;
        for (const idx of track.points) if (idx < out.length) out[idx] = applyTwist(tw, out[idx]);
      } else {
        if (value[0] === 0 && value[1] === 0 && value[2] === 0) continue;
        for (const idx of track.points)
          if (idx < out.length) for (let c = 0; c < 3; ++c) out[idx][c] += value[c];
      }
    }
    return out;
  }

  window.SffdClip = { applyEasing, evaluateTrack, mapClipTime, evaluatePose };
})();
