// The browser side of multiarm's 3D replay (docs/replay.md).
//
// The page holds one JSON document (<script id="multiarm-replay">, format
// "multiarm.replay/1", written by workcell.replay): the cell's arms as
// bodies (capsules, boxes, ... or triangle meshes), their poses sampled on a
// time grid (int16, zlib, base64), the zones and their states over time, the
// tasks and the faults. This script draws the cell with three.js, poses the
// bodies at the slider's time (linear interpolation between samples),
// colours each zone by its state, and draws the Gantt strip with a cursor.
//
// Tools stand at their racks and ride on the arm that holds them.
//
// For tests and embedding it sets window.multiarmReplay = {ready, duration,
// setTime(t), time(), toolAt(name), play(), pause(), error}.

import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const api = { ready: false, duration: 0, error: null };
window.multiarmReplay = api;

function fail(message) {
  api.error = message;
  const box = document.getElementById("replay-error");
  if (box) {
    box.textContent = message;
    box.hidden = false;
  }
}

async function inflate(b64) {
  const raw = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  const stream = new Blob([raw]).stream().pipeThrough(new DecompressionStream("deflate"));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}

async function typed(b64, Kind) {
  const bytes = await inflate(b64);
  return new Kind(bytes.buffer, bytes.byteOffset, bytes.byteLength / Kind.BYTES_PER_ELEMENT);
}

// ------------------------------------------------------------- geometry

function primitive(kind, size) {
  // Local z is the axis of capsules and cylinders (FCL's convention);
  // three.js builds them along y.
  let g;
  if (kind === "capsule") {
    g = new THREE.CapsuleGeometry(size[0], size[1], 6, 16);
    g.rotateX(Math.PI / 2);
  } else if (kind === "cylinder") {
    g = new THREE.CylinderGeometry(size[0], size[0], size[1], 24);
    g.rotateX(Math.PI / 2);
  } else if (kind === "box") {
    g = new THREE.BoxGeometry(size[0], size[1], size[2]);
  } else {
    g = new THREE.SphereGeometry(size[0], 20, 14);
  }
  return g;
}

async function meshGeometry(m) {
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", new THREE.BufferAttribute(await typed(m.vertices, Float32Array), 3));
  g.setIndex(new THREE.BufferAttribute(await typed(m.faces, Uint32Array), 1));
  g.computeVertexNormals();
  return g;
}

// black or white text, whichever reads on ``hex``
function ink(hex) {
  const v = parseInt(hex.slice(1), 16);
  const [r, g, b] = [(v >> 16) & 255, (v >> 8) & 255, v & 255].map((x) => x / 255);
  return 0.299 * r + 0.587 * g + 0.114 * b > 0.55 ? "#000" : "#fff";
}

function matrixOf(rowMajor) {
  const m = new THREE.Matrix4();
  m.set(...rowMajor);
  return m;
}

// ------------------------------------------------------------- the page

async function main() {
  const node = document.getElementById("multiarm-replay");
  if (!node) {
    fail("this page carries no replay data");
    return;
  }
  const data = JSON.parse(node.textContent);
  if (data.format !== "multiarm.replay/1") {
    fail(`unknown replay format ${data.format}`);
    return;
  }
  const view = document.getElementById("view");
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    fail(`this browser cannot draw WebGL: ${e.message}`);
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf7f7f5);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a8a, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(2, -3, 5);
  scene.add(sun);

  const [lo, hi] = data.bounds.map((v) => new THREE.Vector3(...v));
  const centre = lo.clone().add(hi).multiplyScalar(0.5);
  const span = hi.clone().sub(lo);
  const radius = Math.max(span.length() / 2, 0.1);

  const camera = new THREE.PerspectiveCamera(40, 1, radius / 100, radius * 50);
  camera.up.set(0, 0, 1);
  camera.position.copy(centre).add(new THREE.Vector3(0.8, -1.3, 1.9).multiplyScalar(radius * 1.1));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  // the floor: a grid at the lowest z of the cell
  const floor = new THREE.GridHelper(
    Math.max(span.x, span.y) * 1.2,
    12,
    0xbbbbbb,
    0xdddddd,
  );
  floor.rotateX(Math.PI / 2);
  floor.position.set(centre.x, centre.y, lo.z);
  scene.add(floor);

  // ---- zones: translucent solids with an outline, coloured by state
  const stateColour = data.states;
  const zones = data.zones.map((z) => {
    const group = new THREE.Group();
    const fill = new THREE.MeshBasicMaterial({
      color: stateColour.free,
      transparent: true,
      opacity: 0.1,
      depthWrite: false,
      side: THREE.DoubleSide,
    });
    const edge = new THREE.LineBasicMaterial({ color: 0x777777, transparent: true, opacity: 0.6 });
    return { z, group, fill, edge, state: "free" };
  });
  for (const zone of zones) {
    for (const s of zone.z.solids) {
      const g = s.kind === "mesh" ? await meshGeometry(data.meshes[s.mesh]) : primitive(s.kind, s.size);
      const mesh = new THREE.Mesh(g, zone.fill);
      const lines = new THREE.LineSegments(new THREE.EdgesGeometry(g, 25), zone.edge);
      const m = matrixOf(s.transform);
      for (const o of [mesh, lines]) {
        o.applyMatrix4(m);
        o.renderOrder = 2;
        zone.group.add(o);
      }
    }
    scene.add(zone.group);
  }

  // ---- arm bodies
  const armColour = data.arms.map((a) => new THREE.Color(a.colour));
  const armMaterial = armColour.map(
    (c) => new THREE.MeshStandardMaterial({ color: c, roughness: 0.55, metalness: 0.1 }),
  );
  // faults on the arms themselves: an arm that failed for good turns grey
  // with a dark red glow; any other fault of an arm flashes it red (1 s, or
  // as long as the fault lasts)
  const failedAt = data.arms.map(() => Infinity);
  const flashes = data.arms.map(() => []);
  for (const f of data.faults) {
    if (f.arm < 0) continue;
    if (f.kind === "arm_failure") failedAt[f.arm] = Math.min(failedAt[f.arm], f.time);
    else flashes[f.arm].push([f.time, Math.max(f.end, f.time + 1.0)]);
  }
  const grey = new THREE.Color(0x8c8c8c);
  const faultRed = new THREE.Color(0xd62728);
  function faultsAt(t) {
    armMaterial.forEach((m, a) => {
      m.color.copy(armColour[a]);
      m.emissive.set(0x000000);
      if (t >= failedAt[a]) {
        m.color.copy(grey);
        m.emissive.set(0x4a0000);
      } else if (flashes[a].some(([s, e]) => s <= t && t < e)) {
        m.color.copy(faultRed);
        m.emissive.set(0x400000);
      }
    });
  }
  const geometries = new Map();
  const bodies = [];
  for (const b of data.bodies) {
    let g;
    if (b.kind === "mesh") {
      if (!geometries.has(b.mesh)) geometries.set(b.mesh, await meshGeometry(data.meshes[b.mesh]));
      g = geometries.get(b.mesh);
    } else {
      g = primitive(b.kind, b.size);
    }
    const mesh = new THREE.Mesh(g, armMaterial[b.arm]);
    mesh.matrixAutoUpdate = false;
    scene.add(mesh);
    bodies.push(mesh);
  }

  // ---- sampled poses: (bodies, 7, n) int16 = x, y, z quantised on the
  // cell's box, then the unit quaternion x, y, z, w times 32767
  const fr = data.frames;
  const poses = await typed(fr.poses, Int16Array);
  const n = fr.n;
  const B = bodies.length;
  if (poses.length !== B * 7 * n) {
    fail(`replay data: ${poses.length} pose values, expected ${B * 7 * n}`);
    return;
  }
  const pos = new THREE.Vector3();
  const quat = new THREE.Quaternion();
  const q1 = new THREE.Quaternion();
  const one = new THREE.Vector3(1, 1, 1);

  function value(b, c, i) {
    return poses[(b * 7 + c) * n + i];
  }

  function poseAt(t) {
    let f = (t - fr.t0) / fr.dt;
    f = Math.min(Math.max(f, 0), n - 1);
    const i = Math.min(Math.floor(f), n - 2 < 0 ? 0 : n - 2);
    const j = Math.min(i + 1, n - 1);
    const a = f - i;
    for (let b = 0; b < B; b++) {
      const p = [0, 1, 2].map((c) => {
        const v = value(b, c, i) * (1 - a) + value(b, c, j) * a;
        return fr.lo[c] + (v + 32768) * fr.scale[c];
      });
      pos.set(p[0], p[1], p[2]);
      quat.set(value(b, 3, i), value(b, 4, i), value(b, 5, i), value(b, 6, i)).normalize();
      q1.set(value(b, 3, j), value(b, 4, j), value(b, 5, j), value(b, 6, j)).normalize();
      quat.slerp(q1, a);
      bodies[b].matrix.compose(pos, quat, one);
    }
  }

  // ---- tools: a small dark cylinder standing on a plate at its rack; while
  // an arm holds it (the run's tool reservations), carried at the arm's tip
  // body, along that body's z axis
  const toolGeometry = new THREE.CylinderGeometry(0.018, 0.018, 0.12, 16);
  toolGeometry.rotateX(Math.PI / 2);
  const toolMaterial = new THREE.MeshStandardMaterial({ color: 0x2b2b2b, roughness: 0.35, metalness: 0.4 });
  const plateGeometry = new THREE.BoxGeometry(0.08, 0.08, 0.01);
  const plateMaterial = new THREE.MeshStandardMaterial({ color: 0x6b6b6b, roughness: 0.8 });
  const tools = (data.tools || []).map((tool) => {
    const mesh = new THREE.Mesh(toolGeometry, toolMaterial);
    mesh.matrixAutoUpdate = false;
    scene.add(mesh);
    const plate = new THREE.Mesh(plateGeometry, plateMaterial);
    plate.position.set(tool.rack[0], tool.rack[1], tool.rack[2] - 0.065);
    scene.add(plate);
    return { tool, mesh, arm: -1 };
  });
  function toolsAt(t) {
    for (const entry of tools) {
      const h = entry.tool.held.find((x) => x.start <= t && t < x.end);
      const tip = h ? data.arms[h.arm].tip : -1;
      if (h && tip !== undefined && tip >= 0) {
        entry.mesh.matrix.copy(bodies[tip].matrix);
        entry.arm = h.arm;
      } else {
        entry.mesh.matrix.makeTranslation(...entry.tool.rack);
        entry.arm = -1;
      }
      entry.mesh.matrixWorldNeedsUpdate = true;
    }
  }
  function toolAt(name) {
    const entry = tools.find((x) => x.tool.name === name);
    if (!entry) return null;
    const p = new THREE.Vector3().setFromMatrixPosition(entry.mesh.matrix);
    return { position: [p.x, p.y, p.z], arm: entry.arm };
  }

  // ---- zone states over time
  const intervals = data.zone_states;
  const rank = { waiting: 3, moving: 2, occupied: 1 };
  function zonesAt(t) {
    const now = zones.map(() => null);
    for (const s of intervals) {
      if (s.start <= t && t < s.end && s.zone < zones.length) {
        const cur = now[s.zone];
        if (!cur || rank[s.state] > rank[cur.state]) now[s.zone] = s;
      }
    }
    zones.forEach((zone, k) => {
      const s = now[k];
      const state = s ? s.state : "free";
      zone.state = state;
      zone.holder = s ? s.arm : -1;
      zone.fill.color.set(stateColour[state]);
      zone.fill.opacity = state === "free" ? 0.1 : 0.38;
      zone.edge.color.set(s && s.arm >= 0 ? armColour[s.arm] : 0x777777);
      // space-grid blocks are many: drawn only while in use
      if (zone.z.grid) zone.group.visible = state !== "free";
    });
  }

  // ---- the Gantt strip
  const gantt = document.getElementById("gantt");
  const ctx = gantt.getContext("2d");
  const lanes = data.arms.map((a) => a.name);
  const hasCellFaults = data.faults.some((f) => f.arm < 0);
  if (hasCellFaults) lanes.push("whole cell");
  const T = Math.max(data.duration, 1e-9);
  const labelW = 110;
  const laneH = 22;
  const axisH = 18;
  function ganttSize() {
    const w = gantt.parentElement.clientWidth;
    const h = lanes.length * laneH + axisH + 4;
    const dpr = window.devicePixelRatio || 1;
    gantt.width = Math.round(w * dpr);
    gantt.height = Math.round(h * dpr);
    gantt.style.width = `${w}px`;
    gantt.style.height = `${h}px`;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return [w, h];
  }
  let gw = 0;
  let gh = 0;
  const xOf = (t) => labelW + ((gw - labelW - 8) * t) / T;
  const timeOf = (x) => ((x - labelW) * T) / Math.max(gw - labelW - 8, 1);

  function drawMark(kind, x, y, colour) {
    const s = 6;
    ctx.fillStyle = colour;
    ctx.strokeStyle = "#000";
    ctx.lineWidth = 1;
    ctx.beginPath();
    const sym = (data.fault_marks[kind] || data.fault_marks.other).symbol;
    if (sym === "X") {
      ctx.moveTo(x - s, y - s); ctx.lineTo(x + s, y + s);
      ctx.moveTo(x + s, y - s); ctx.lineTo(x - s, y + s);
      ctx.strokeStyle = colour; ctx.lineWidth = 3; ctx.stroke();
      return;
    }
    if (sym === "*") {
      for (let k = 0; k < 10; k++) {
        const r = k % 2 ? s * 0.45 : s * 1.1;
        const a = -Math.PI / 2 + (k * Math.PI) / 5;
        ctx[k ? "lineTo" : "moveTo"](x + r * Math.cos(a), y + r * Math.sin(a));
      }
    } else if (sym === "D") {
      ctx.moveTo(x, y - s); ctx.lineTo(x + s, y); ctx.lineTo(x, y + s); ctx.lineTo(x - s, y);
    } else if (sym === "v") {
      ctx.moveTo(x - s, y - s * 0.7); ctx.lineTo(x + s, y - s * 0.7); ctx.lineTo(x, y + s * 0.8);
    } else if (sym === "^") {
      ctx.moveTo(x - s, y + s * 0.7); ctx.lineTo(x + s, y + s * 0.7); ctx.lineTo(x, y - s * 0.8);
    } else if (sym === "s") {
      ctx.rect(x - s * 0.8, y - s * 0.8, s * 1.6, s * 1.6);
    } else if (sym === "o") {
      ctx.arc(x, y, s * 0.8, 0, 2 * Math.PI);
    } else {
      ctx.rect(x - s, y - s * 0.3, 2 * s, s * 0.6);
      ctx.rect(x - s * 0.3, y - s, s * 0.6, 2 * s);
    }
    ctx.closePath();
    ctx.fill();
    ctx.stroke();
  }

  function drawGantt(t) {
    ctx.clearRect(0, 0, gw, gh);
    ctx.font = "11px sans-serif";
    ctx.textBaseline = "middle";
    lanes.forEach((name, k) => {
      const y = k * laneH;
      ctx.fillStyle = k % 2 ? "#f4f4f4" : "#fbfbfb";
      ctx.fillRect(0, y, gw, laneH);
      ctx.fillStyle = k < data.arms.length ? data.arms[k].colour : "#444";
      ctx.fillText(name, 4, y + laneH / 2, labelW - 8);
    });
    const barH = laneH - 9;
    for (const task of data.tasks) {
      const y = task.arm * laneH + 3;
      const colour = data.arms[task.arm].colour;
      // the plan: a thin light strip under the bars of the arm it was planned on
      if (task.planned_end > task.planned_start) {
        const pa = task.planned_arm ?? task.arm;
        ctx.fillStyle = data.arms[pa].colour;
        ctx.globalAlpha = 0.4;
        const p0 = xOf(task.planned_start);
        ctx.fillRect(p0, pa * laneH + 3 + barH + 2, Math.max(xOf(task.planned_end) - p0 - 1, 1), 3);
        ctx.globalAlpha = 1;
      }
      let x0;
      let x1;
      let fill;
      if (task.start !== null && task.end > task.start) {
        x0 = xOf(task.start);
        x1 = Math.max(xOf(task.end), x0 + 1);
        fill = task.status === "failed" ? "#d62728" : colour;
        ctx.fillStyle = fill;
        ctx.fillRect(x0, y, x1 - x0, barH);
        ctx.strokeStyle = "rgba(0,0,0,0.55)";
        ctx.lineWidth = 0.8;
        ctx.setLineDash([]);
        ctx.strokeRect(x0, y, x1 - x0, barH);
      } else if (task.status === "failed" && task.planned_end > task.planned_start) {
        // never ran: its planned slot, outlined in red
        x0 = xOf(task.planned_start);
        x1 = Math.max(xOf(task.planned_end), x0 + 1);
        fill = "#fde8e8";
        ctx.fillStyle = fill;
        ctx.fillRect(x0, y, x1 - x0, barH);
        ctx.strokeStyle = "#d62728";
        ctx.lineWidth = 1;
        ctx.setLineDash([3, 2]);
        ctx.strokeRect(x0, y, x1 - x0, barH);
        ctx.setLineDash([]);
      } else {
        continue;
      }
      const w = ctx.measureText(task.task).width;
      if (w < x1 - x0 - 4) {
        ctx.fillStyle = ink(fill);
        ctx.fillText(task.task, x0 + 2, y + barH / 2);
      }
    }
    for (const f of data.faults) {
      const k = f.arm >= 0 ? f.arm : lanes.length - 1;
      const y = k * laneH + laneH / 2;
      if (f.end > f.time) {
        ctx.fillStyle = "rgba(214,39,40,0.25)";
        ctx.fillRect(xOf(f.time), k * laneH, xOf(f.end) - xOf(f.time), laneH);
      }
      drawMark(f.kind, xOf(f.time), y, "#d62728");
    }
    // time axis
    const y0 = lanes.length * laneH;
    ctx.fillStyle = "#333";
    ctx.strokeStyle = "#999";
    const step = niceStep(T / 8);
    for (let s = 0; s <= T + 1e-9; s += step) {
      const x = xOf(s);
      ctx.beginPath(); ctx.moveTo(x, y0); ctx.lineTo(x, y0 + 4); ctx.stroke();
      ctx.fillText(`${+s.toFixed(3)}`, x - 6, y0 + 11);
    }
    ctx.fillText("time (s)", 4, y0 + 11);
    // cursor
    const xc = xOf(t);
    ctx.strokeStyle = "#000";
    ctx.lineWidth = 2;
    ctx.beginPath(); ctx.moveTo(xc, 0); ctx.lineTo(xc, y0); ctx.stroke();
  }

  function niceStep(x) {
    const p = 10 ** Math.floor(Math.log10(Math.max(x, 1e-9)));
    for (const m of [1, 2, 5, 10]) if (m * p >= x) return m * p;
    return 10 * p;
  }

  // ---- the status line: what each arm does now
  const status = document.getElementById("status");
  function statusAt(t) {
    const parts = data.arms.map((a, k) => {
      const task = data.tasks.find((x) => x.arm === k && x.start <= t && t < x.end);
      const wait = intervals.find((s) => s.arm === k && s.state === "waiting" && s.start <= t && t < s.end);
      let what = task ? task.task : "idle";
      if (t >= failedAt[k]) what = `failed at ${failedAt[k].toFixed(2)} s`;
      if (wait) what += ` (waiting for ${data.zones[wait.zone] ? data.zones[wait.zone].name : wait.name})`;
      return `<span style="color:${a.colour}">&#9632;</span> ${a.name}: ${what}`;
    });
    const faults = data.faults.filter((f) => f.time <= t).length;
    status.innerHTML = parts.join(" &nbsp; ") + (faults ? ` &nbsp; faults so far: ${faults}` : "");
  }

  // ---- time, slider, play and pause
  const slider = document.getElementById("time");
  const label = document.getElementById("clock");
  const button = document.getElementById("play");
  const speed = document.getElementById("speed");
  slider.min = "0";
  slider.max = String(T);
  slider.step = String(Math.max(fr.dt / 2, T / 10000));
  let now = 0;
  let playing = false;
  let last = 0;

  function resize() {
    const w = view.clientWidth;
    const h = view.clientHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
    [gw, gh] = ganttSize();
  }

  function show(t) {
    now = Math.min(Math.max(t, 0), T);
    poseAt(now);
    toolsAt(now);
    zonesAt(now);
    faultsAt(now);
    drawGantt(now);
    statusAt(now);
    slider.value = String(now);
    label.textContent = `${now.toFixed(2)} s / ${T.toFixed(2)} s`;
    renderer.render(scene, camera);
  }

  function tick(ms) {
    if (!playing) return;
    const dt = last ? (ms - last) / 1000 : 0;
    last = ms;
    const next = now + dt * Number(speed.value);
    show(next >= T ? T : next);
    if (next >= T) pause();
    else requestAnimationFrame(tick);
  }
  function play() {
    if (playing) return;
    if (now >= T) now = 0;
    playing = true;
    last = 0;
    button.textContent = "Pause";
    requestAnimationFrame(tick);
  }
  function pause() {
    playing = false;
    button.textContent = "Play";
  }
  button.addEventListener("click", () => (playing ? pause() : play()));
  slider.addEventListener("input", () => {
    pause();
    show(Number(slider.value));
  });
  gantt.addEventListener("click", (ev) => {
    const r = gantt.getBoundingClientRect();
    pause();
    show(timeOf(ev.clientX - r.left));
  });
  // the space bar plays and pauses (unless a control that uses it has the focus)
  window.addEventListener("keydown", (ev) => {
    const tag = document.activeElement ? document.activeElement.tagName : "";
    if (ev.key === " " && tag !== "BUTTON" && tag !== "SELECT") {
      ev.preventDefault();
      if (playing) pause();
      else play();
    }
  });
  controls.addEventListener("change", () => renderer.render(scene, camera));
  window.addEventListener("resize", () => {
    resize();
    show(now);
  });

  resize();
  show(0);
  Object.assign(api, {
    duration: T,
    setTime: (t) => {
      pause();
      show(t);
    },
    time: () => now,
    toolAt,
    play,
    pause,
    ready: true,
  });
  document.body.dataset.ready = "true";
}

main().catch((e) => fail(`replay failed: ${e && e.message ? e.message : e}`));
