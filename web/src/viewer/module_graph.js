// module_graph.js - loads an ES module graph in a Worker with the page's import map applied.
// Chromium does not apply a page's import map inside workers, and the decoder imports `fzstd` and
// `hash-wasm` by bare name: each module of the graph is fetched, its bare specifiers replaced by the
// mapped URLs and its relative ones by the Blob URLs of the (rewritten) modules they name. An import
// that closes a cycle (container.js and file.js import each other) gets a small module of functions
// that call the named module's exports once it has loaded: enough for functions called later, not
// for values read while the modules load.

const IMPORT = /((?:^|[;\n}])\s*(?:import|export)\b[^'";]*?\bfrom\s*|(?:^|[;\n])\s*import\s*)(['"])([^'"\n]+)\2/g;

/**
 * Imports `url` with `imports` ({bare name: absolute URL}) standing in for the import map.
 * @returns {Promise<object>} the module namespace
 */
export async function importMapped(url, imports) {
  const blobs = new Map(), loading = new Set(), proxied = new Set();
  const registry = (globalThis.__vffModules ??= {});
  const proxy = (u, clause) => {
    proxied.add(u);
    const names = (clause.match(/\{([^}]*)\}/)?.[1] ?? '').split(',').map((n) => n.trim().split(/\s+as\s+/)[0]).filter(Boolean);
    const src = names.map((n) => `export function ${n}(...a) { return globalThis.__vffModules[${JSON.stringify(u)}].${n}(...a); }`).join('\n');
    return URL.createObjectURL(new Blob([src], { type: 'text/javascript' }));
  };
  const load = async (u, clause = '') => {
    if (loading.has(u)) return proxy(u, clause);
    if (!blobs.has(u)) {
      loading.add(u);
      blobs.set(u, (async () => {
        const res = await fetch(u);
        if (!res.ok) throw new Error(`${u}: HTTP ${res.status}`);
        const src = await res.text();
        const parts = [];
        let last = 0;
        for (const m of src.matchAll(IMPORT)) {
          const spec = m[3];
          let to;
          if (spec in imports) to = imports[spec];
          else if (/^\.{1,2}\//.test(spec)) to = await load(new URL(spec, u).href, m[1]);
          else to = new URL(spec, u).href;
          const at = m.index + m[1].length + 1;
          parts.push(src.slice(last, at), to);
          last = at + spec.length;
        }
        parts.push(src.slice(last), `\n//# sourceURL=${u}`);
        loading.delete(u);
        return URL.createObjectURL(new Blob(parts, { type: 'text/javascript' }));
      })());
    }
    return blobs.get(u);
  };
  const root = await import(await load(new URL(url).href));
  for (const u of proxied) registry[u] = await import(await blobs.get(u));
  return root;
}
