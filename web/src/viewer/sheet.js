// sheet.js - the contact sheet of a field's distance maps (decode.js draws it in the Worker): zoom
// (wheel, pinch-free +/- keys), pan (pointer drag, touch, arrow keys), the map and texel under the
// pointer named (asked of the Worker, which holds the file). Painted at most once per animation frame.
export class ContactSheet {
  constructor(canvas, label, askTexel) {
    this.canvas = canvas;
    this.label = label;
    this.askTexel = askTexel;
    this.image = null;
    this.raf = 0;
    this.zoom = 1; this.ox = 0; this.oy = 0;
    new ResizeObserver(() => this.request()).observe(canvas);
    canvas.addEventListener('wheel', (e) => { e.preventDefault(); this.zoomAt(e.offsetX, e.offsetY, e.deltaY < 0 ? 1.25 : 0.8); }, { passive: false });
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => { drag = [e.clientX - this.ox, e.clientY - this.oy]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener('pointerup', () => { drag = null; });
    canvas.addEventListener('pointercancel', () => { drag = null; });
    canvas.addEventListener('pointermove', (e) => {
      if (drag) { this.ox = e.clientX - drag[0]; this.oy = e.clientY - drag[1]; this.request(); }
      this.hover(e.offsetX, e.offsetY);
    });
    canvas.addEventListener('keydown', (e) => {
      const step = 40;
      const moves = { ArrowLeft: [step, 0], ArrowRight: [-step, 0], ArrowUp: [0, step], ArrowDown: [0, -step] };
      if (moves[e.key]) { this.ox += moves[e.key][0]; this.oy += moves[e.key][1]; this.request(); }
      else if (e.key === '+' || e.key === '=') this.zoomAt(canvas.clientWidth / 2, canvas.clientHeight / 2, 1.25);
      else if (e.key === '-') this.zoomAt(canvas.clientWidth / 2, canvas.clientHeight / 2, 0.8);
      else return;
      e.preventDefault();
    });
  }

  /** Shows a sheet ({rgba, width, height, cols, M, shown, mapCount}) or nothing (null). */
  set(sheet) {
    this.image = null;
    this.label.textContent = '';
    if (sheet) {
      const src = new OffscreenCanvas(sheet.width, sheet.height);
      src.getContext('2d').putImageData(new ImageData(sheet.rgba, sheet.width, sheet.height), 0, 0);
      this.image = { src, ...sheet };
      this.zoom = Math.min(this.canvas.clientWidth / sheet.width, this.canvas.clientHeight / sheet.height) || 1;
      this.ox = 0; this.oy = 0;
    }
    this.request();
  }

  zoomAt(x, y, f) {
    this.ox = x - (x - this.ox) * f; this.oy = y - (y - this.oy) * f; this.zoom *= f;
    this.request();
  }

  request() { if (!this.raf) this.raf = requestAnimationFrame(() => { this.raf = 0; this.paint(); }); }

  paint() {
    const c = this.canvas, dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const ctx = c.getContext('2d');
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.imageSmoothingEnabled = false;
    ctx.fillStyle = '#222';
    ctx.fillRect(0, 0, c.clientWidth, c.clientHeight);
    if (this.image) ctx.drawImage(this.image.src, this.ox, this.oy, this.image.width * this.zoom, this.image.height * this.zoom);
  }

  async hover(px, py) {
    const s = this.image;
    if (!s) return;
    const x = Math.floor((px - this.ox) / this.zoom), y = Math.floor((py - this.oy) / this.zoom);
    const M = s.M, k = Math.floor(y / (M + 1)) * s.cols + Math.floor(x / (M + 1)), i = x % (M + 1), j = y % (M + 1);
    if (x < 0 || y < 0 || i >= M || j >= M || k >= s.shown || Math.floor(x / (M + 1)) >= s.cols) { this.label.textContent = ''; return; }
    const text = await this.askTexel(k, i, j);
    if (this.image === s) this.label.textContent = text;
  }
}
