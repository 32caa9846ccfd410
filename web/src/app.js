// app.js - the viewer page's entry point. The page needs web/node_modules (`npm ci` in web/: three,
// fzstd, hash-wasm); without them a module import would fail silently, so they are checked first
// and the page says what is missing and how to install it. Then the viewer starts (viewer/main.js).
const NEEDED = { three: 'three/build/three.module.js', fzstd: 'fzstd/esm/index.mjs', 'hash-wasm': 'hash-wasm/dist/index.esm.js' };

async function missingDependencies() {
  const missing = [];
  for (const [name, path] of Object.entries(NEEDED)) {
    const res = await fetch(new URL(`../node_modules/${path}`, import.meta.url), { method: 'HEAD' }).catch(() => null);
    if (!res || !res.ok) missing.push(name);
  }
  return missing;
}

const missing = await missingDependencies();
if (missing.length) {
  const box = document.getElementById('deps');
  box.hidden = false;
  box.querySelector('.which').textContent = missing.join(', ');
  for (const el of document.querySelectorAll('input, select, button')) el.disabled = true;
  window.vffViewer = { missing };
} else {
  await import('./viewer/main.js');
}
