// The labelling page: shows the round's camera image, draws the gripper at the cursor, and
// sends clicks, turns and confirms to the server, which keeps all the state.
"use strict";

const view = document.getElementById("view");
const ctx = view.getContext("2d");
const film = document.getElementById("film");
const filmCtx = film.getContext("2d");
const $ = (id) => document.getElementById(id);

let state = null;
let roundImage = null;
let roundId = null;
let lastId = null;
let hover = null;
let scale = 5;
let playing = null;

async function api(method, path, body) {
  const response = await fetch(path, {
    method,
    headers: body ? { "Content-Type": "application/json" } : {},
    body: body ? JSON.stringify(body) : undefined,
  });
  const data = await response.json().catch(() => ({}));
  if (!response.ok) {
    $("error").textContent = data.error || `${method} ${path}: ${response.status}`;
    return null;
  }
  $("error").textContent = "";
  return data;
}

// The two finger points: the pixel centre ∓ the finger offset along θ, as the server draws them.
function gripper(u, v, angle, alpha) {
  const s = scale;
  const cx = (u + 0.5) * s, cy = (v + 0.5) * s;
  const t = (angle * Math.PI) / 180;
  const dx = Math.cos(t) * state.finger_offset_px * s, dy = Math.sin(t) * state.finger_offset_px * s;
  const px = -Math.sin(t), py = Math.cos(t);
  const half = (state.pad_px * s) / 2;
  ctx.globalAlpha = alpha;
  ctx.lineWidth = 2;
  ctx.strokeStyle = "rgb(255,40,40)";
  ctx.beginPath();
  ctx.moveTo(cx - dx, cy - dy);
  ctx.lineTo(cx + dx, cy + dy);
  ctx.stroke();
  ctx.lineWidth = 5;
  ctx.strokeStyle = "rgb(40,220,40)";
  for (const sign of [-1, 1]) {
    const fx = cx + sign * dx, fy = cy + sign * dy;
    ctx.beginPath();
    ctx.moveTo(fx - px * half, fy - py * half);
    ctx.lineTo(fx + px * half, fy + py * half);
    ctx.stroke();
  }
  ctx.fillStyle = "rgb(255,255,0)";
  ctx.fillRect(u * s, v * s, s, s);
  ctx.globalAlpha = 1;
}

function draw() {
  ctx.imageSmoothingEnabled = false;
  ctx.fillStyle = "#000";
  ctx.fillRect(0, 0, view.width, view.height);
  if (roundImage && state && state.phase === "done") {
    // The last round's image, dimmed: nothing left to click.
    ctx.globalAlpha = 0.3;
    ctx.drawImage(roundImage, 0, 0, view.width, view.height);
    ctx.globalAlpha = 1;
    ctx.fillStyle = "#fff";
    ctx.font = "600 28px system-ui, sans-serif";
    ctx.textAlign = "center";
    ctx.fillText("Every object has its labels", view.width / 2, view.height / 2);
  } else if (roundImage && state && state.round) {
    ctx.drawImage(roundImage, 0, 0, view.width, view.height);
    const angle = state.cursor.angle;
    if (state.cursor.centre) gripper(state.cursor.centre[0], state.cursor.centre[1], angle, 1);
    if (hover && state.phase === "waiting") gripper(hover[0], hover[1], angle, 0.45);
  }
}

function pixelAt(event) {
  const rect = view.getBoundingClientRect();
  const x = Math.floor(((event.clientX - rect.left) / rect.width) * state.image_size);
  const y = Math.floor(((event.clientY - rect.top) / rect.height) * state.image_size);
  return [Math.min(Math.max(x, 0), state.image_size - 1), Math.min(Math.max(y, 0), state.image_size - 1)];
}

function statusText(s) {
  switch (s.phase) {
    case "waiting": return "Click the grasp centre, turn with A/D, confirm with Q or Enter.";
    case "running": return "Running the attempt in the simulator…";
    case "done": return "Every object has its labels. The dataset is complete; Ctrl-C in the terminal stops the server.";
    default: return "Dropping the next object…";
  }
}

function showProgress(d) {
  const body = $("progress").querySelector("tbody");
  body.innerHTML = "";
  for (const o of d.objects) {
    const row = document.createElement("tr");
    row.innerHTML = `<td></td><td class="num">${o.labels} / ${d.per_object}</td><td class="num">${o.rounds}</td>`;
    row.firstChild.textContent = o.object;
    body.appendChild(row);
  }
  $("overall").textContent = `${d.labelled} / ${d.wanted}`;
}

function showOutcome(last) {
  const box = $("outcome");
  const where = `${last.object}, round ${last.round}`;
  box.className = "outcome " + (last.stored ? "success" : "failure");
  box.textContent = last.stored
    ? `${where}: success, stored as a label.`
    : `${where}: ${last.reason}${last.detail ? " (" + last.detail + ")" : ""}; not stored.`;
  box.dataset.id = last.id;
  box.dataset.reason = last.reason;
  if (last.frames > 0) play(last);
}

// The attempt's frames arrive as one tall JPEG; step through it.
function play(last) {
  const strip = new Image();
  strip.onload = () => {
    if (playing) clearInterval(playing);
    film.width = last.frame_width;
    film.height = last.frame_height;
    let i = 0;
    playing = setInterval(() => {
      filmCtx.drawImage(strip, 0, i * last.frame_height, last.frame_width, last.frame_height, 0, 0, film.width, film.height);
      i += 1;
      if (i >= last.frames) { clearInterval(playing); playing = null; }
    }, 50);
  };
  strip.src = `/api/attempt.jpg?id=${last.id}`;
}

async function refresh() {
  const s = await api("GET", "/api/state");
  if (!s) return;
  state = s;
  scale = view.width / s.image_size;
  $("status").textContent = statusText(s);
  $("status").className = "status" + (s.phase === "done" ? " done" : "");
  $("object").textContent = s.round ? s.round.object : s.phase === "done" ? "Dataset complete" : "…";
  $("round").textContent = s.round ? `round ${s.round.round}` : "";
  $("angle").textContent = s.cursor.angle.toFixed(1);
  $("centre").textContent = s.cursor.centre ? `(${s.cursor.centre[0]}, ${s.cursor.centre[1]})` : "none";
  document.body.dataset.phase = s.phase;
  showProgress(s.dataset);
  if (s.last && s.last.id !== lastId) {
    lastId = s.last.id;
    showOutcome(s.last);
  }
  const id = s.round ? s.round.id : null;
  if (id !== roundId) {
    roundId = id;
    // Between rounds (and once done) the last image stays, so the page does not flash.
    if (id !== null) {
      const img = new Image();
      img.onload = () => { if (roundId === id) { roundImage = img; draw(); } };
      img.src = `/api/round.png?id=${id}`;
    }
  }
  draw();
}

view.addEventListener("mousemove", (e) => { if (state) { hover = pixelAt(e); draw(); } });
view.addEventListener("mouseleave", () => { hover = null; draw(); });
view.addEventListener("click", async (e) => {
  if (!state || state.phase !== "waiting") return;
  const [x, y] = pixelAt(e);
  if (await api("POST", "/api/click", { x, y })) refresh();
});
view.addEventListener("wheel", async (e) => {
  e.preventDefault();
  if (await api("POST", "/api/rotate", { steps: e.deltaY > 0 ? 1 : -1 })) refresh();
}, { passive: false });
document.addEventListener("keydown", async (e) => {
  if (!state) return;
  const key = e.key.toLowerCase();
  if (key === "a" || key === "d") {
    if (await api("POST", "/api/rotate", { steps: key === "d" ? 1 : -1 })) refresh();
  } else if ((key === "q" || key === "enter") && state.round) {
    e.preventDefault();
    if (await api("POST", "/api/confirm", { round_id: state.round.id })) refresh();
  }
});

refresh();
setInterval(refresh, 250);
