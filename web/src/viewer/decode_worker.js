// decode_worker.js - the viewer's decoding Worker: opens and checks a .vff off the page's thread and
// sends back what the page draws (decode.js), with progress; then answers the contact sheet's
// questions about single texels. Messages: {init: {imports, decode}} once, then
// {decode: {bytes, name, limits}} -> {progress: {share, stage}}* then {result} or {failure};
// {texel: {k, i, j, id}} -> {texel: {id, text}}.
import { importMapped } from './module_graph.js';

let decoder = null, opened = null;
self.onmessage = async ({ data }) => {
  try {
    if (data.init) {
      decoder = await importMapped(data.init.decode, data.init.imports);
      self.postMessage({ ready: true });
    } else if (data.decode) {
      const { bytes, name, limits } = data.decode;
      opened = null;
      const progress = (share, stage) => self.postMessage({ progress: { share, stage } });
      const { result, file, transfer } = await decoder.decodeForViewer(bytes, name, limits, progress);
      opened = file;
      self.postMessage({ result }, transfer);
    } else if (data.texel) {
      const { k, i, j, id } = data.texel;
      self.postMessage({ texel: { id, text: opened ? decoder.texelText(opened, k, i, j) : '' } });
    }
  } catch (e) {
    self.postMessage({ failure: { message: String(e?.message ?? e), stack: String(e?.stack ?? '') } });
  }
};
