// SplatFFD web player: PlayCanvas draws the capture; every frame the clip's pose (clip.js) goes into a
// float texture of control-point displacements and the gsplat shader hook (ffd_glsl.js) deforms each
// Gaussian on the GPU: centre through f, covariance through J Sigma J^T.
//
// PlayCanvas sorts Gaussians on the CPU (a worker) by their centres; it does not see where the shader
// moves them, so the player evaluates the deformed centres here (f only, the same sum as the shader) and
// hands them to the sorter whenever the pose changes (at most every 100 ms while playing).
//
// URL parameters: t=SECONDS (playback time) or frame=K (K / fps), paused=1, bare=1 (no control bar),
// bg=R,G,B (sRGB 0..1, default black). window.sffdReady turns true once the frame of the current pose
// has been drawn with the sort of that pose (tests take screenshots then); window.sffdError holds what
// went wrong, if anything.
"use strict";
(function () {
  const scene = window.SFFD_SCENE, capture = window.SFFD_CAPTURE;
  const params = new URLSearchParams(location.search);
  const errorBox = document.getElementById("error");
  window.sffdReady = false;
  window.sffdError = null;

  function fail(message) {
    window.sffdError = String(message);
    errorBox.textContent = "SplatFFD player: " + message;
  }
  if (!window.pc) return fail("playcanvas.min.js did not load");
  if (!scene || !capture) return fail("scene.js or capture.js did not load");
  if (params.get("bare") === "1") document.body.classList.add("bare");

  const [width, height] = scene.size;
  const fps = scene.fps || 24;
  const clip = scene.clip;
  const lattice = scene.lattice;
  const rest = lattice.rest;
  const [L, M, N] = lattice.divisions;
  const bspline = lattice.basis === "bspline";
  const rate = (scene.playback_speed ?? 1) * (clip.speed ?? 1);  // clip seconds per playback second
  const length = rate !== 0 ? clip.duration / Math.abs(rate) : clip.duration;

  // ---- lattice frame: M^-1 by rows, as the C++ side builds it ----
  function inverse3(S, T, U) {
    // columns S, T, U; returns rows of the inverse
    const a = S, b = T, c = U;
    const bc = [b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]];
    const ca = [c[1] * a[2] - c[2] * a[1], c[2] * a[0] - c[0] * a[2], c[0] * a[1] - c[1] * a[0]];
    const ab = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const det = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
    return [bc.map((v) => v / det), ca.map((v) => v / det), ab.map((v) => v / det)];
  }
  const minv = inverse3(lattice.axes[0], lattice.axes[1], lattice.axes[2]);
  const origin = lattice.origin;

  // ---- PlayCanvas ----
  const canvas = document.getElementById("view");
  canvas.width = width;
  canvas.height = height;
  canvas.style.width = width + "px";
  canvas.style.height = height + "px";
  let app;
  try {
    app = new pc.Application(canvas, {
      graphicsDeviceOptions: { antialias: false, alpha: false, preserveDrawingBuffer: true, deviceTypes: ["webgl2"] },
    });
  } catch (e) {
    return fail("WebGL 2 is not available: " + e);
  }
  app.graphicsDevice.maxPixelRatio = 1;
  app.setCanvasFillMode(pc.FILLMODE_NONE, width, height);
  app.setCanvasResolution(pc.RESOLUTION_FIXED, width, height);

  const bg = (params.get("bg") || "0,0,0").split(",").map(Number);
  const cam = scene.camera;
  const camera = new pc.Entity("camera");
  camera.addComponent("camera", {
    clearColor: new pc.Color(bg[0] || 0, bg[1] || 0, bg[2] || 0, 1),
    fov: cam.fov_y_degrees,
    nearClip: cam.near,
    farClip: cam.far,
    frustumCulling: false,  // the deformed cloud leaves its rest box
  });
  camera.setPosition(cam.eye[0], cam.eye[1], cam.eye[2]);
  camera.lookAt(new pc.Vec3(cam.target[0], cam.target[1], cam.target[2]), new pc.Vec3(cam.up[0], cam.up[1], cam.up[2]));
  app.root.addChild(camera);

  // Control-point displacements (pose - rest), 64 texels a row.
  const texRows = Math.ceil(rest.length / 64);
  const points = new pc.Texture(app.graphicsDevice, {
    name: "ffdPoints", width: 64, height: texRows, format: pc.PIXELFORMAT_RGBA32F, mipmaps: false,
    minFilter: pc.FILTER_NEAREST, magFilter: pc.FILTER_NEAREST,
    addressU: pc.ADDRESS_CLAMP_TO_EDGE, addressV: pc.ADDRESS_CLAMP_TO_EDGE,
  });
  const dp = new Float64Array(rest.length * 3);  // current displacements, for the CPU centres too

  // The clip runs in the lattice's frame; the displacements go to the cloud's through to_cloud's linear
  // part (the identity when the lattice sits with its cloud).
  const toCloud = lattice.to_cloud || [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]];
  function setPose(pose) {
    const texels = points.lock();
    texels.fill(0);
    for (let i = 0; i < rest.length; ++i) {
      const d = [pose[i][0] - rest[i][0], pose[i][1] - rest[i][1], pose[i][2] - rest[i][2]];
      for (let c = 0; c < 3; ++c) {
        const r = toCloud[c];
        dp[3 * i + c] = r[0] * d[0] + r[1] * d[1] + r[2] * d[2];
        texels[4 * i + c] = dp[3 * i + c];
      }
    }
    points.unlock();
  }

  // ---- CPU centres for the sorter: the shader's f, in double ----
  function bernstein(s, n, out) {
    const r = 1 - s;
    let c = 1;
    for (let i = 0; i <= n; ++i) {
      out[i] = c * Math.pow(s, i) * Math.pow(r, n - i);
      c = (c * (n - i)) / (i + 1);
    }
  }
  function bsplineWeights(f) {
    const f2 = f * f, f3 = f2 * f, r = 1 - f;
    return [r * r * r / 6, (3 * f3 - 6 * f2 + 4) / 6, (-3 * f3 + 3 * f2 + 3 * f + 1) / 6, f3 / 6];
  }
  const bs = new Float64Array(L + 1), bt = new Float64Array(M + 1), bu = new Float64Array(N + 1);
  function deformCentres(src, dst) {
    const slack = 1e-6;
    for (let p = 0; p < src.length; p += 3) {
      const x = src[p] - origin[0], y = src[p + 1] - origin[1], z = src[p + 2] - origin[2];
      let s = minv[0][0] * x + minv[0][1] * y + minv[0][2] * z;
      let t = minv[1][0] * x + minv[1][1] * y + minv[1][2] * z;
      let u = minv[2][0] * x + minv[2][1] * y + minv[2][2] * z;
      dst[p] = src[p], dst[p + 1] = src[p + 1], dst[p + 2] = src[p + 2];
      if (s < -slack || t < -slack || u < -slack || s > 1 + slack || t > 1 + slack || u > 1 + slack) continue;
      s = Math.min(Math.max(s, 0), 1), t = Math.min(Math.max(t, 0), 1), u = Math.min(Math.max(u, 0), 1);
      let dx = 0, dy = 0, dz = 0;
      if (!bspline) {
        bernstein(s, L, bs), bernstein(t, M, bt), bernstein(u, N, bu);
        for (let i = 0; i <= L; ++i)
          for (let j = 0; j <= M; ++j) {
            const w = bs[i] * bt[j];
            let base = ((i * (M + 1) + j) * (N + 1)) * 3;
            for (let k = 0; k <= N; ++k, base += 3) {
              const b = w * bu[k];
              dx += b * dp[base], dy += b * dp[base + 1], dz += b * dp[base + 2];
            }
          }
      } else {
        const g = [s * L, t * M, u * N], n = [L, M, N];
        const c = g.map((v, a) => Math.min(Math.floor(v), n[a] - 1));
        const ws = bsplineWeights(g[0] - c[0]), wt = bsplineWeights(g[1] - c[1]), wu = bsplineWeights(g[2] - c[2]);
        for (let a = 0; a < 4; ++a) {
          const i = c[0] + a - 1;
          if (i < 0 || i > L) continue;
          for (let b = 0; b < 4; ++b) {
            const j = c[1] + b - 1;
            if (j < 0 || j > M) continue;
            for (let k = 0; k < 4; ++k) {
              const kk = c[2] + k - 1;
              if (kk < 0 || kk > N) continue;
              const w = ws[a] * wt[b] * wu[k], base = ((i * (M + 1) + j) * (N + 1) + kk) * 3;
              dx += w * dp[base], dy += w * dp[base + 1], dz += w * dp[base + 2];
            }
          }
        }
      }
      dst[p] += dx, dst[p + 1] += dy, dst[p + 2] += dz;
    }
  }

  // ---- the capture ----
  function decodeBase64(text) {
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return bytes;
  }
  const bytes = decodeBase64(capture.base64);
  const filename = "capture." + capture.format;
  // The bytes are handed over as the asset's contents: nothing is fetched (file:// forbids it).
  const asset = new pc.Asset("capture", "gsplat", { url: filename, filename, contents: new Response(bytes) });

  let playing = params.get("paused") !== "1";
  let time = Number(params.get("t") ?? (params.has("frame") ? Number(params.get("frame")) / fps : 0));
  if (!Number.isFinite(time)) time = 0;
  let shownTime = NaN, sortedTime = NaN, lastSortAt = -Infinity;
  let sorter = null, restCentres = null, deformed = null;
  let sortPending = false, framesSinceSort = -1;

  const playButton = document.getElementById("play");
  const scrub = document.getElementById("scrub");
  const label = document.getElementById("time");
  scrub.max = String(length);
  scrub.step = String(1 / fps);
  function syncControls() {
    playButton.textContent = playing ? "Pause" : "Play";
    scrub.value = String(time);
    label.textContent = time.toFixed(3) + " s / " + length.toFixed(3) + " s";
  }
  playButton.addEventListener("click", () => { playing = !playing; syncControls(); });
  scrub.addEventListener("input", () => { time = Number(scrub.value); playing = false; syncControls(); });

  function clipTimeAt(t) {
    return window.SffdClip.mapClipTime(clip, t * rate);
  }

  function requestSort(now) {
    if (!sorter) return;
    deformCentres(restCentres, deformed);
    sorter.centers.set(deformed);
    sorter.setMapping(null);  // posts the centres: the worker re-sorts (forceUpdate)
    sortedTime = shownTime;
    sortPending = true;
    framesSinceSort = -1;
    lastSortAt = now;
  }

  app.assets.add(asset);
  asset.once("error", (e) => fail("the capture did not load: " + e));
  asset.ready(() => {
    const entity = new pc.Entity("capture");
    entity.addComponent("gsplat", { unified: false });
    const tr = scene.transform;
    entity.setLocalPosition(tr.translation[0], tr.translation[1], tr.translation[2]);
    entity.setLocalRotation(new pc.Quat(tr.rotation[1], tr.rotation[2], tr.rotation[3], tr.rotation[0]));
    entity.setLocalScale(tr.scale[0], tr.scale[1], tr.scale[2]);
    app.root.addChild(entity);
    entity.gsplat.asset = asset;
    const instance = entity.gsplat.instance;
    if (!instance) return fail("PlayCanvas made no gsplat instance");
    const material = instance.material;
    material.getShaderChunks(pc.SHADERLANGUAGE_GLSL).set("gsplatModifyVS", window.SFFD_FFD_GLSL);
    material.setParameter("uFfdPoints", points);
    material.setParameter("uFfdMinv0", new Float32Array(minv[0]));
    material.setParameter("uFfdMinv1", new Float32Array(minv[1]));
    material.setParameter("uFfdMinv2", new Float32Array(minv[2]));
    material.setParameter("uFfdOrigin", new Float32Array(origin));
    material.setParameter("uFfdDiv", new Float32Array([L, M, N, bspline ? 1 : 0]));
    material.update();
    sorter = instance.sorter;
    if (!sorter) return fail("PlayCanvas made no sorter for the capture");
    restCentres = new Float64Array(instance.resource.centers);
    deformed = new Float32Array(restCentres.length);
    sorter.on("updated", () => { if (sortPending) { sortPending = false; framesSinceSort = 0; } });
    shownTime = NaN;
  });
  app.assets.load(asset);

  app.on("update", (dt) => {
    if (playing) {
      time += dt;
      if (clip.mode === "once" && time > length) time = length;
      else if (time > length && clip.mode !== "once") time -= length * Math.floor(time / length);
    }
    if (time !== shownTime && sorter) {
      shownTime = time;
      window.sffdReady = false;
      const ct = clipTimeAt(time);
      setPose(window.SffdClip.evaluatePose(clip, rest, ct));
      window.sffdState = { time, clipTime: ct };
      const now = performance.now();
      if (!playing || now - lastSortAt > 100) requestSort(now);
    } else if (sorter && sortedTime !== shownTime && !sortPending) {
      requestSort(performance.now());  // playing stopped between sorts: sort the pose on screen
    }
    syncControls();
  });
  // Ready: the sort of the shown pose arrived, was applied by the next frame, and one more was drawn.
  app.on("frameend", () => {
    if (framesSinceSort < 0 || sortPending) return;
    if (sorter && sorter.pendingSorted) return;
    if (++framesSinceSort >= 2 && sortedTime === shownTime) window.sffdReady = !playing;
  });
  app.start();
  syncControls();
})();
