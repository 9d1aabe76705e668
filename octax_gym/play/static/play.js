// octax-gym play: draws the frames the server sends and sends the keys. The env runs on the server.
// window.octaxPlay exposes what the page received and measured, for tests and curious users.
"use strict";
(() => {
  const LOG_MAX = 20000;
  const KEYPAD = [0x1, 0x2, 0x3, 0xC, 0x4, 0x5, 0x6, 0xD, 0x7, 0x8, 0x9, 0xE, 0xA, 0x0, 0xB, 0xF];
  const play = window.octaxPlay = {
    hello: null, state: null, last: null, log: [], latencies: [], errors: [], drawn: 0,
    connected: false, keysDown: new Set(),
  };
  const $ = (id) => document.getElementById(id);
  const canvas = $("screen"), ctx = canvas.getContext("2d");
  let small = null, smallCtx = null, image = null, scale = 1, palette = [];
  let queue = [];            // frames waiting for their time: {pixels, due, msg, first}
  let keyboard = {};         // keyboard key -> CHIP-8 key
  let seq = 0;
  const pending = new Map(); // seq -> time of the key press, until a frame shows it
  let ws = null;

  function send(obj) { if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(obj)); }

  function connect() {
    ws = new WebSocket(`ws://${location.host}/ws`);
    ws.onopen = () => { play.connected = true; $("status").textContent = "connected"; };
    ws.onclose = (e) => {
      play.connected = false;
      $("status").textContent = `disconnected (${e.code}${e.reason ? ": " + e.reason : ""}); reload to play again`;
    };
    ws.onmessage = (e) => {
      const msg = JSON.parse(e.data);
      if (msg.type === "hello") setup(msg);
      else if (msg.type === "state") showState(msg);
      else if (msg.type === "frame") frame(msg);
      else if (msg.type === "error") { play.errors.push(msg.message); $("error").textContent = msg.message; }
    };
  }

  function setup(hello) {
    play.hello = hello;
    keyboard = hello.keyboard;
    palette = hello.palette;
    scale = Math.max(1, Math.floor(Math.min(640 / hello.width, 320 / hello.height)));
    canvas.width = hello.width * scale;
    canvas.height = hello.height * scale;
    small = document.createElement("canvas");
    small.width = hello.width; small.height = hello.height;
    smallCtx = small.getContext("2d");
    image = smallCtx.createImageData(hello.width, hello.height);
    document.title = `${hello.title} · octax-gym play`;
    $("title").textContent = hello.title;
    $("status").textContent = `${hello.game} · ${hello.platform.toUpperCase()} · connected`;
    $("description").textContent = hello.description;
    $("recording").hidden = !hello.recording;
    const seats = $("seats");
    seats.textContent = "";
    const used = new Set();
    hello.seats.forEach((seat, index) => {
      const box = document.createElement("div");
      box.className = "seat";
      const label = document.createElement("label");
      label.textContent = `${hello.seats.length > 1 ? seat.name : "player"}: `;
      const select = document.createElement("select");
      select.id = `seat${index}`;
      for (const player of hello.players) {
        const option = document.createElement("option");
        option.value = option.textContent = player;
        select.appendChild(option);
      }
      select.onchange = () => send({type: "seat", seat: index, player: select.value});
      label.appendChild(select);
      box.appendChild(label);
      const table = document.createElement("table");
      table.innerHTML = "<tr><th>action</th><th>CHIP-8 key</th><th>keyboard</th></tr><tr><td>0</td><td>none</td><td>–</td></tr>";
      for (const a of seat.actions) {
        used.add(a.chip8);
        const row = table.insertRow();
        for (const text of [a.action, a.chip8.toString(16).toUpperCase(), a.keyboard]) row.insertCell().textContent = text;
      }
      box.appendChild(table);
      seats.appendChild(box);
    });
    const pad = $("keypad");
    pad.textContent = "";
    const keyOf = Object.fromEntries(Object.entries(keyboard).map(([k, v]) => [v, k]));
    for (const key of KEYPAD) {
      const cell = document.createElement("div");
      cell.id = `key${key}`;
      cell.className = used.has(key) ? "used" : "";
      cell.innerHTML = `${key.toString(16).toUpperCase()}<small>${keyOf[key].toUpperCase()}</small>`;
      pad.appendChild(cell);
    }
  }

  function showState(state) {
    play.state = state;
    $("pause").textContent = state.paused ? "resume" : "pause";
    $("speed").value = String(state.speed);
    state.players.forEach((player, i) => { const s = $(`seat${i}`); if (s) s.value = player; });
    if (state.fps) $("fps").textContent = state.fps.toFixed(1);
    overlay();
  }

  function frame(msg) {
    play.last = msg;
    if (play.log.length >= LOG_MAX) play.log.splice(0, play.log.length - LOG_MAX + 1);
    play.log.push(msg);
    if (!play.hello) return;
    const raw = atob(msg.frames), bytes = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
    const size = play.hello.width * play.hello.height;
    const count = bytes.length / size;
    const speed = play.state ? play.state.speed : 1;
    const period = 1000 / play.hello.frames_per_second / speed;
    const now = performance.now();
    if (queue.length > 4 * count) queue = queue.slice(-count); // far behind: drop, never lag
    // A step before the first (reset) has one screen worth showing: its last.
    const first = msg.step === 0 ? count - 1 : 0;
    for (let i = first; i < count; i++) {
      queue.push({pixels: bytes.subarray(i * size, (i + 1) * size), due: now + (i - first) * period, msg, first: i === first});
    }
    stats(msg);
  }

  function stats(msg) {
    $("score").textContent = msg.score.join(" : ");
    $("lives").textContent = msg.lives < 0 ? "–" : msg.lives;
    $("return").textContent = msg.return.map((r) => r.toFixed(0)).join(" : ");
    $("step").textContent = msg.step;
    $("episode").textContent = `${msg.episode} (${msg.seed})`;
    if (msg.fps) $("fps").textContent = msg.fps.toFixed(1);
    overlay();
  }

  function overlay() {
    const box = $("overlay");
    if (play.last && play.last.done) { box.hidden = false; box.textContent = "game over · Enter or reset for a new episode"; }
    else if (play.state && play.state.paused) { box.hidden = false; box.textContent = "paused · Space to resume"; }
    else box.hidden = true;
  }

  function draw(item) {
    const data = image.data, pixels = item.pixels;
    for (let i = 0; i < pixels.length; i++) {
      const c = palette[pixels[i]] || palette[0];
      data[4 * i] = c[0]; data[4 * i + 1] = c[1]; data[4 * i + 2] = c[2]; data[4 * i + 3] = 255;
    }
    smallCtx.putImageData(image, 0, 0);
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(small, 0, 0, canvas.width, canvas.height);
    play.drawn++;
    play.drawnStep = [item.msg.episode, item.msg.step];
    if (item.first && pending.size) {
      const now = performance.now();
      for (const [s, t] of pending) {
        if (item.msg.seq >= s) {
          play.latencies.push({seq: s, ms: now - t, step: item.msg.step});
          pending.delete(s);
        }
      }
      const recent = play.latencies.slice(-20).map((l) => l.ms).sort((a, b) => a - b);
      if (recent.length) $("latency").textContent = `${recent[recent.length >> 1].toFixed(0)} ms`;
    }
  }

  function tick() {
    const now = performance.now();
    let item = null;
    while (queue.length && queue[0].due <= now) {
      const next = queue.shift();
      if (item && item.first) draw(item); // a step's first frame is always drawn (latency is timed on it)
      item = next;
    }
    if (item) draw(item);
    requestAnimationFrame(tick);
  }

  function keyEvent(e, down) {
    if (e.ctrlKey || e.metaKey || e.altKey) return;
    const name = e.key.length === 1 ? e.key.toLowerCase() : e.key;
    if (name in keyboard) {
      e.preventDefault();
      if (e.repeat) return;
      const key = keyboard[name];
      if (down) play.keysDown.add(key); else play.keysDown.delete(key);
      const cell = $(`key${key}`);
      if (cell) cell.classList.toggle("held", down);
      seq++;
      if (down) pending.set(seq, performance.now());
      send({type: "key", key, down, seq});
    } else if (down && name === " ") { e.preventDefault(); togglePause(); }
    else if (down && name === "Enter") { e.preventDefault(); send({type: "reset"}); }
    else if (down && name === ".") { e.preventDefault(); send({type: "step"}); }
  }

  function togglePause() { send({type: "pause", paused: !(play.state && play.state.paused)}); }

  document.addEventListener("keydown", (e) => keyEvent(e, true));
  document.addEventListener("keyup", (e) => keyEvent(e, false));
  window.addEventListener("blur", () => {
    for (const key of play.keysDown) { seq++; send({type: "key", key, down: false, seq}); }
    play.keysDown.clear();
    document.querySelectorAll("#keypad .held").forEach((c) => c.classList.remove("held"));
  });
  $("pause").onclick = (e) => { togglePause(); e.target.blur(); };
  $("single").onclick = (e) => { send({type: "step"}); e.target.blur(); };
  $("reset").onclick = (e) => { send({type: "reset"}); e.target.blur(); };
  $("speed").onchange = (e) => { send({type: "speed", speed: Number(e.target.value)}); e.target.blur(); };
  requestAnimationFrame(tick);
  connect();
})();
