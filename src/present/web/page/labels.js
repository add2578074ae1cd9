// The labels page: every stored label with its grasp drawn, filterable by object; delete
// renumbers the object's later labels on the server in one crash-safe step.
"use strict";

const grid = document.getElementById("grid");
const filter = document.getElementById("filter");
let version = 0;

async function load(data) {
  if (!data) {
    const response = await fetch("/api/labels");
    data = await response.json();
    if (!response.ok) { document.getElementById("error").textContent = data.error; return; }
  }
  version += 1;
  document.getElementById("summary").textContent = `${data.total} labels in ${data.labels_dir}`;
  const chosen = filter.value;
  filter.length = 1;
  for (const o of data.objects) filter.add(new Option(`${o.object} (${o.labels.length})`, o.object, false, o.object === chosen));
  grid.innerHTML = "";
  for (const o of data.objects) {
    if (chosen && o.object !== chosen) continue;
    for (const l of o.labels) {
      const figure = document.createElement("figure");
      const img = document.createElement("img");
      img.src = `/api/labels/${encodeURIComponent(o.object)}/${l.k}.png?v=${version}`;
      img.alt = `${o.object} label ${l.k}`;
      const caption = document.createElement("figcaption");
      const text = document.createElement("span");
      text.textContent = `${o.object} ${l.k} · (${l.x}, ${l.y}) ${l.angle.toFixed(1)}°${l.source ? " · " + l.source : ""}`;
      const button = document.createElement("button");
      button.textContent = "Delete";
      button.onclick = () => remove(o.object, l.k);
      caption.append(text, button);
      figure.append(img, caption);
      grid.appendChild(figure);
    }
  }
}

async function remove(object, k) {
  if (!window.confirm(`Delete ${object} label ${k}? Its later labels move down one number.`)) return;
  const response = await fetch(`/api/labels/${encodeURIComponent(object)}/${k}`, { method: "DELETE" });
  const data = await response.json();
  if (!response.ok) { document.getElementById("error").textContent = data.error; return; }
  document.getElementById("error").textContent = "";
  load(data);
}

filter.onchange = () => load();
load();
