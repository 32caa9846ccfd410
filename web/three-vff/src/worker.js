// worker.js - decodes a .vff off the main thread: decodeInWorker(bytes, onProgress) runs decode.js
// in a module Worker and resolves to the data VffField.fromDecoded takes, with progress events.
//
// Import maps do not reach workers (browsers apply them to documents only), and the decoder imports
// 'fzstd' and 'hash-wasm' by bare name. So the worker's module graph is copied into blob: URLs with
// every specifier resolved here, where the page's import map applies (import.meta.resolve). An
// import cycle (container.js <-> file.js) is closed through a small module of live bindings that
// the worker fills once the graph has loaded.

const STATEMENT = /^[ \t]*(?:import|export)\b([^'";]*?)\bfrom\s*(['"])([^'"\n]+)\2|^[ \t]*import\s*(['"])([^'"\n]+)\4/gm;

async function fetchGraph(entry, resolveBare) {
  const modules = new Map();
  const todo = [entry];
  while (todo.length) {
    const url = todo.pop();
    if (modules.has(url)) continue;
    const res = await fetch(url);
    if (!res.ok) throw new Error(`the decode worker's module ${url} cannot be loaded (${res.status})`);
    const src = await res.text();
    const deps = [];
    for (const m of src.matchAll(STATEMENT)) {
      const spec = m[3] ?? m[5], clause = m[1] ?? '';
      const relative = spec.startsWith('.') || spec.startsWith('/');
      const target = relative ? new URL(spec, url).href : resolveBare(spec);
      const at = m.index + m[0].lastIndexOf(spec);
      deps.push({ spec, at, target, inGraph: relative, clause });
      if (relative) todo.push(target);
    }
    modules.set(url, { src, deps });
  }
  return modules;
}

/** The names a named import clause `{ a, b as c }` takes from its module. */
function importedNames(clause) {
  const m = /\{([^}]*)\}/.exec(clause);
  if (!m || /\*/.test(clause)) throw new Error(`an import cycle through '${clause.trim()}': only named imports can close a cycle`);
  return m[1].split(',').map((s) => s.trim().split(/\s+as\s+/)[0]).filter(Boolean);
}

/** blob: URLs for the graph from `entry`; returns {url, binds: [[shimUrl, targetUrl]]}. */
function toBlobs(modules, entry) {
  const done = new Map(), stack = [], binds = [];
  const blob = (text) => URL.createObjectURL(new Blob([text], { type: 'text/javascript' }));
  const visit = (url) => {
    if (done.has(url)) return done.get(url);
    stack.push(url);
    const { src, deps } = modules.get(url);
    let out = '', last = 0;
    for (const d of deps.slice().sort((a, b) => a.at - b.at)) {
      let to = d.target;
      if (d.inGraph) {
        if (stack.includes(d.target)) {
          const names = importedNames(d.clause);
          to = blob(`export let ${names.join(', ')};\nexport function __vffBind(m) { ${names.map((n) => `${n} = m.${n};`).join(' ')} }\n`);
          binds.push([to, d.target]);
        } else to = visit(d.target);
      }
      out += src.slice(last, d.at) + to;
      last = d.at + d.spec.length;
    }
    out += src.slice(last);
    stack.pop();
    const u = blob(out);
    done.set(url, u);
    return u;
  };
  const url = visit(entry);
  return { url, binds: binds.map(([shim, target]) => [shim, done.get(target)]) };
}

const BODY = `
self.onmessage = async ({ data: { bytes, limits } }) => {
  try {
    const { data } = await decodeVff(bytes, { limits, onProgress: (p) => self.postMessage({ progress: p }) });
    self.postMessage({ data }, transferables(data));
  } catch (e) {
    self.postMessage({ error: { name: e.name, message: e.message, id: e.id, codeName: e.codeName, section: e.section, offset: e.offset, detail: e.detail } });
  }
};
`;

let workerUrl = null;

async function buildWorker(imports) {
  const resolveBare = (spec) => {
    if (imports[spec]) return new URL(imports[spec], location.href).href;
    try { return import.meta.resolve(spec); } catch { throw new Error(`the decode worker needs '${spec}': give options.imports['${spec}'] or an import map entry`); }
  };
  const entry = new URL('./decode.js', import.meta.url).href;
  const { url, binds } = toBlobs(await fetchGraph(entry, resolveBare), entry);
  const lines = [`import { decodeVff, transferables } from '${url}';`];
  binds.forEach(([shim, target], i) => lines.push(`import { __vffBind as bind${i} } from '${shim}';`, `import * as target${i} from '${target}';`, `bind${i}(target${i});`));
  return URL.createObjectURL(new Blob([lines.join('\n') + BODY], { type: 'text/javascript' }));
}

/**
 * Decodes `bytes` (Uint8Array or ArrayBuffer; a copy is posted, the caller's stays usable) in a
 * Worker. onProgress({stage, done, total}) reports 'open', 'check', 'textures' (layers composed) and
 * 'done'. options.limits: the context's limits (decode.js); options.imports: URLs of 'fzstd' and
 * 'hash-wasm' where the page has no import map for them. Resolves to {field, layout, note,
 * metadata, textures}; rejects with an Error carrying the decoder's {name, id, codeName, section,
 * offset, detail}.
 */
export async function decodeInWorker(bytes, onProgress = null, options = {}) {
  workerUrl ??= buildWorker(options.imports ?? {});
  let url;
  try {
    url = await workerUrl;
  } catch (e) {
    workerUrl = null;
    throw e;
  }
  const worker = new Worker(url, { type: 'module' });
  const copy = (bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes)).slice();
  return new Promise((resolve, reject) => {
    worker.onmessage = ({ data }) => {
      if (data.progress) { onProgress?.(data.progress); return; }
      worker.terminate();
      if (data.error) reject(Object.assign(new Error(data.error.message), data.error));
      else resolve(data.data);
    };
    worker.onerror = (e) => { worker.terminate(); reject(new Error(`the decode worker failed: ${e.message ?? 'it could not start'}`)); };
    worker.postMessage({ bytes: copy, limits: options.limits ?? null }, [copy.buffer]);
  });
}
