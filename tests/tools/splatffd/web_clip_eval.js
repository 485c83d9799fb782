// The player's clip evaluation (content/web/player/clip.js) outside the browser, for the C++ comparison in
// web_export_test.cpp: node web_clip_eval.js PLAYER_DIR T1 [T2 ...] prints, as one JSON line, for each
// playback time T the mapped clip time and the control points, evaluated as the page does (scene.js's
// clip and rest points, playback rate = playback_speed * clip.speed).
"use strict";
const fs = require("fs");
const path = require("path");
const vm = require("vm");
const [dir, ...times] = process.argv.slice(2);
const context = { window: {}, Math, Number, console };
vm.createContext(context);
for (const f of ["clip.js", "scene.js"]) vm.runInContext(fs.readFileSync(path.join(dir, f), "utf8"), context, { filename: f });
const scene = context.window.SFFD_SCENE, clip = scene.clip, api = context.window.SffdClip;
const rate = (scene.playback_speed ?? 1) * (clip.speed ?? 1);
const out = times.map(Number).map((t) => {
  const ct = api.mapClipTime(clip, t * rate);
  return { t, clip_time: ct, points: api.evaluatePose(clip, scene.lattice.rest, ct) };
});
process.stdout.write(JSON.stringify(out) + "\n");
