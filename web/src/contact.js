// contact.js - the zoomable contact sheet of a field's distance maps: near hits bright, far hits
// dark, misses magenta; the map and texel under the cursor are named.

const MISS = [230, 0, 200];

/** Draws every map into one RGBA image, `cols` maps per row. */
export function sheetImage(file) {
  const M = file.field.mapResolution, n = file.field.mapCount;
  const cols = Math.ceil(Math.sqrt(n)), rows = Math.ceil(n / cols);
  const W = cols * (M + 1), H = rows * (M + 1);
  const img = new ImageData(W, H);
  img.data.fill(40);
  for (let k = 0; k < n; ++k) {
    const d = file.distances(k), x0 = (k % cols) * (M + 1), y0 = Math.floor(k / cols) * (M + 1);
    const scale = file.field.distanceEncoding === 4 ? 1 : 2 * file.field.sphere.radius;
    for (let j = 0; j < M; ++j)
      for (let i = 0; i < M; ++i) {
        const v = d[j * M + i], o = 4 * ((y0 + j) * W + x0 + i);
        const g = Number.isNaN(v) ? null : Math.round(255 * (1 - 0.85 * Math.min(v / scale, 1)));
        const rgb = g === null ? MISS : [g, g, g];
        img.data[o] = rgb[0]; img.data[o + 1] = rgb[1]; img.data[o + 2] = rgb[2]; img.data[o + 3] = 255;
      }
  }
  return { img, cols, M };
}

/** Shows the sheet in `canvas` with wheel zoom and drag pan; names the map under the cursor. */
export function attachSheet(canvas, file, label) {
  const { img, cols, M } = sheetImage(file);
  const src = new OffscreenCanvas(img.width, img.height);
  src.getContext('2d').putImageData(img, 0, 0);
  let zoom = Math.min(canvas.clientWidth / img.width, canvas.clientHeight / img.height) || 1, ox = 0, oy = 0;
  const ctx = canvas.getContext('2d');
  const paint = () => {
    canvas.width = canvas.clientWidth; canvas.height = canvas.clientHeight;
    ctx.imageSmoothingEnabled = false;
    ctx.fillStyle = '#222'; ctx.fillRect(0, 0, canvas.width, canvas.height);
    ctx.drawImage(src, ox, oy, img.width * zoom, img.height * zoom);
  };
  canvas.onwheel = (e) => {
    e.preventDefault();
    const f = e.deltaY < 0 ? 1.25 : 0.8;
    ox = e.offsetX - (e.offsetX - ox) * f; oy = e.offsetY - (e.offsetY - oy) * f; zoom *= f;
    paint();
  };
  let drag = null;
  canvas.onmousedown = (e) => { drag = [e.clientX - ox, e.clientY - oy]; };
  window.addEventListener('mouseup', () => { drag = null; });
  canvas.onmousemove = (e) => {
    if (drag) { ox = e.clientX - drag[0]; oy = e.clientY - drag[1]; paint(); }
    const x = Math.floor((e.offsetX - ox) / zoom), y = Math.floor((e.offsetY - oy) / zoom);
    const k = Math.floor(y / (M + 1)) * cols + Math.floor(x / (M + 1));
    const i = x % (M + 1), j = y % (M + 1);
    if (x < 0 || y < 0 || i >= M || j >= M || k >= file.field.mapCount || Math.floor(x / (M + 1)) >= cols) { label.textContent = ''; return; }
    const d = file.distance(k, i, j);
    label.textContent = `map ${k}, texel (${i}, ${j}): ${d === null ? 'miss' : file.field.distanceEncoding === 4 ? 'hit' : `hit at ${d.toPrecision(6)}`}`;
  };
  paint();
}
