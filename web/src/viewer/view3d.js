// view3d.js - the three.js view of a field: its object drawn from the field (impostor.js) standing
// on the ground at the object's lowest point, the ground's AO and soft shadow accumulated over
// frames while the view holds still, orbit controls (pointer, touch, arrow keys), sized to its
// container at the device's pixel ratio, redrawn at most once per animation frame. Where the page
// gives it a WebGPU device (useWebGpu), the ground is webgpu_ground.js's, in a canvas under this
// one, and three.js draws the object and the grid over it; otherwise the ground is a WebGL2 pass.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { createVffImpostor } from '../../three-vff/src/impostor.js';
import { accumulatePass, floatTarget, lowestPoint, referenceView } from './passes.js';
import { WebGpuGround } from './webgpu_ground.js';

const GROUND_VERTEX = `
void main() { gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }`;
const GROUND_FRAGMENT = `
uniform sampler2D uAccumulated;
uniform int uShow;             // 0 shaded, 1 AO, 2 shadow
uniform vec3 uLight;
uniform vec3 uColor;
uniform vec3 uSky;
uniform float uFade;           // distance from the camera's target where the ground fades into the sky
uniform vec3 uTarget;
in vec3 vWorld;
out highp vec4 fragColor;
void main() {
  vec2 v = texelFetch(uAccumulated, ivec2(gl_FragCoord.xy), 0).rg;
  vec3 col;
  if (uShow == 1) col = vec3(v.x);
  else if (uShow == 2) col = vec3(v.y);
  else col = uColor * (0.55 * v.x + 0.6 * v.y * max(uLight.y, 0.0));
  float f = smoothstep(0.6 * uFade, uFade, length(vWorld.xz - uTarget.xz));
  fragColor = vec4(mix(col, uSky, f), 1.0);
}`;

/** The light from its azimuth and elevation (radians), a unit vector towards it. */
export function lightDirection(azimuth, elevation) {
  return new THREE.Vector3(Math.cos(elevation) * Math.sin(azimuth), Math.sin(elevation), Math.cos(elevation) * Math.cos(azimuth));
}

// Colours go to the screen as written (the shaders' values and the background alike).
THREE.ColorManagement.enabled = false;

export class FieldView {
  /** container: the element the canvas fills; onFrame(info) after each drawn frame. */
  constructor(canvas, container, onFrame = () => {}) {
    this.canvas = canvas;
    this.container = container;
    this.onFrame = onFrame;
    this.onBackend = () => {};  // called when backendName changes (the ground moved to WebGPU or back)
    // (alpha: over a WebGPU ground the canvas is cleared to transparent; otherwise to the sky.)
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true, alpha: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    this.renderer.setClearColor(0xcfd8e3);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xcfd8e3);
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false;
    this.controls.maxPolarAngle = Math.PI / 2 - 0.02;  // never below the ground
    this.controls.addEventListener('change', () => this.invalidate());
    this.options = { interpolated: true, show: 0, aoRaysPerFrame: 2, shadowRaysPerFrame: 1, maxFrames: 64, lightAzimuth: -0.8, lightElevation: 0.9, lightAngle: 0.12 };
    this.frame = 0;
    this.raf = 0;
    this.field = null;
    this.gpuGround = null;  // webgpu_ground.js's WebGpuGround, while the page has a WebGPU device
    this.gpuField = false;  // whether the ground of this field is the WebGPU one
    this.gpuPending = false;  // whether it will be, once the WebGPU passes are compiled
    this.targets = [];
    this.kept = [];     // this field's pass materials, retired with it
    this.retired = [];  // the previous field's materials, disposed once this field has drawn
    canvas.addEventListener('keydown', (e) => this.key(e));
    this.resizeObserver = new ResizeObserver(() => this.resize());
    this.resizeObserver.observe(container);
    this.resize();
  }

  /** Matches the drawing buffer to the container's CSS size times the device pixel ratio. */
  resize() {
    const w = Math.max(1, Math.floor(this.container.clientWidth)), h = Math.max(1, Math.floor(this.container.clientHeight));
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    const size = this.renderer.getDrawingBufferSize(new THREE.Vector2());
    for (const t of this.targets) t.dispose();
    this.targets = [floatTarget(size.x, size.y, this.renderer), floatTarget(size.x, size.y, this.renderer)];
    this.gpuGround?.resize(size.x, size.y);
    this.invalidate();
  }

  /**
   * Draws the ground through WebGPU from now on (gpu: webgpu_ground.js's openWebGpu result with a
   * device), in a canvas put under this one; null goes back to WebGL2. A lost device goes back too.
   */
  useWebGpu(gpu) {
    if (this.gpuGround) {
      this.gpuGround.canvas.remove();
      this.gpuGround.dispose();
      this.gpuGround = null;
    }
    if (gpu?.device) {
      const under = document.createElement('canvas');
      under.className = 'under';
      under.setAttribute('aria-hidden', 'true');
      this.container.prepend(under);
      this.gpuGround = new WebGpuGround(gpu, under);
      this.gpuLimits = gpu.limits;
      gpu.device.lost.then((info) => {
        if (this.gpuGround?.device !== gpu.device) return;
        console.warn(`WebGPU device lost (${info.message}); the ground is drawn with WebGL2`);
        this.useWebGpu(null);
      });
      const size = this.renderer.getDrawingBufferSize(new THREE.Vector2());
      this.gpuGround.resize(size.x, size.y);
    }
    if (this.field) this.placeGround();
    this.invalidate();
  }

  /** Which API draws the ground: 'webgpu' or 'webgl2', and the WebGPU adapter's name. */
  get backend() { return this.gpuField ? 'webgpu' : 'webgl2'; }
  get backendName() {
    if (this.gpuField) return `WebGPU (${this.gpuGround.name})`;
    return this.gpuPending ? 'WebGL2 (the WebGPU passes are compiling)' : 'WebGL2';
  }

  /** Whether a field's slices fit the WebGPU device's limits (else its ground stays WebGL2). */
  fitsWebGpu(g) {
    const l = this.gpuLimits, d = g.distance;
    const side = g.is3d ? l.max3d : l.maxTextureSize;
    return d.width <= side && d.height <= side && d.depth <= (g.is3d ? l.max3d : l.maxLayers);
  }

  /** The ground of the current field: the WebGPU one where it can be, else the WebGL2 mesh. */
  placeGround() {
    const g = this.gpuGround, src = this.field.source;
    const fits = !!g && !!src && this.fitsWebGpu(src);
    this.gpuField = fits && g.ready(src.is3d);
    this.gpuPending = fits && !this.gpuField;
    // Until the passes are compiled (3D fields' on first use), WebGL2 draws the ground.
    if (this.gpuPending)
      g.compile(src.is3d).then(() => { if (this.field?.source === src && this.gpuGround === g) { this.placeGround(); this.invalidate(); } },
        (e) => { this.gpuPending = false; console.warn(`the WebGPU ground failed to compile (${e.message}); it stays WebGL2`); this.onBackend(); });
    g?.setField(this.gpuField ? src : null);
    this.ground.visible = !this.gpuField;
    this.scene.background = this.gpuField ? null : new THREE.Color(0xcfd8e3);
    this.renderer.setClearColor(0xcfd8e3, this.gpuField ? 0 : 1);
    this.onBackend();
  }

  /** Shows a field (field_three.js's resources); returns {groundY, lowest}. */
  setField(field) {
    this.clear();
    this.field = field;
    const c = field.center, R = field.radius;
    const low = lowestPoint(this.renderer, field, 96, this.kept);
    this.groundY = low ? low.y : c.y - R;
    this.lowest = low;
    this.impostor = createVffImpostor(field, { interpolated: this.options.interpolated });
    this.scene.add(this.impostor);
    this.groundMaterial = new THREE.ShaderMaterial({
      glslVersion: THREE.GLSL3,
      uniforms: {
        uAccumulated: { value: null }, uShow: { value: 0 }, uLight: { value: new THREE.Vector3() },
        uColor: { value: new THREE.Color(0xe6e1d8) }, uSky: { value: new THREE.Color(0xcfd8e3) },
        uFade: { value: 12 * R }, uTarget: { value: c.clone() },
      },
      vertexShader: `out vec3 vWorld;\n${GROUND_VERTEX.replace('void main() {', 'void main() { vWorld = (modelMatrix * vec4(position, 1.0)).xyz;')}`,
      fragmentShader: GROUND_FRAGMENT,
    });
    this.ground = new THREE.Mesh(new THREE.PlaneGeometry(40 * R, 40 * R), this.groundMaterial);
    this.ground.rotation.x = -Math.PI / 2;
    this.ground.position.set(c.x, this.groundY, c.z);
    this.scene.add(this.ground);
    this.grid = new THREE.GridHelper(24 * R, 24, 0x9a9a9a, 0xbdbdbd);
    this.grid.position.set(c.x, this.groundY + 1e-4 * R, c.z);
    this.grid.material.transparent = true;
    this.grid.material.opacity = 0.35;
    this.scene.add(this.grid);
    this.accumulate = accumulatePass(field);
    this.placeGround();
    this.camera.near = R / 100;
    this.camera.far = R * 200;
    this.controls.target.set(c.x, (this.groundY + c.y + R) / 2, c.z);
    this.camera.position.copy(this.controls.target).add(new THREE.Vector3(0.55, 0.35, 0.75).normalize().multiplyScalar(this.framingDistance()));
    this.controls.minDistance = 0.3 * R;
    this.controls.maxDistance = 30 * R;
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.setOptions({});
    return { groundY: this.groundY, lowest: low };
  }

  /** The camera distance at which the bounding sphere fits the narrower of the two fields of view. */
  framingDistance() {
    const v = THREE.MathUtils.degToRad(this.camera.fov), h = 2 * Math.atan(Math.tan(v / 2) * this.camera.aspect);
    return (1.15 * this.field.radius) / Math.sin(Math.min(v, h) / 2);
  }

  /**
   * Removes the field's object and ground: the empty view. Its materials are retired, not disposed,
   * until the next field has drawn a frame: three.js shares a compiled program among live materials
   * of the same source, so a next field of the same schemes and encodings (sizes are uniforms)
   * compiles nothing, where shader compiles are the slowest step of opening a file.
   */
  clear() {
    for (const o of [this.impostor, this.ground, this.grid]) if (o) { this.scene.remove(o); o.geometry.dispose(); this.retired.push(o.material); }
    this.accumulate?.dispose(this.retired);
    this.retired.push(...this.kept);
    this.kept = [];
    // A retired material is never drawn again: its textures go, so that the old field's data is not
    // held while the next file loads (or after it fails).
    for (const m of this.retired) for (const u of Object.values(m.uniforms ?? {})) if (u.value?.isTexture) u.value = null;
    this.field?.dispose();
    this.gpuGround?.setField(null);
    this.gpuField = this.gpuPending = false;
    this.impostor = this.ground = this.grid = this.accumulate = this.field = null;
    this.invalidate();
  }

  setOptions(o) {
    Object.assign(this.options, o);
    if (this.impostor) {
      const u = this.impostor.material.uniforms;
      u.uInterpolated.value = this.options.interpolated;
      u.uLight.value.copy(lightDirection(this.options.lightAzimuth, this.options.lightElevation));
    }
    this.invalidate();
  }

  /** Arrow keys orbit, +/- zoom (the canvas has keyboard focus). */
  key(e) {
    const step = e.shiftKey ? 0.2 : 0.05;
    const offset = this.camera.position.clone().sub(this.controls.target);
    const s = new THREE.Spherical().setFromVector3(offset);
    if (e.key === 'ArrowLeft') s.theta -= step;
    else if (e.key === 'ArrowRight') s.theta += step;
    else if (e.key === 'ArrowUp') s.phi = Math.max(0.05, s.phi - step);
    else if (e.key === 'ArrowDown') s.phi = Math.min(this.controls.maxPolarAngle, s.phi + step);
    else if (e.key === '+' || e.key === '=') s.radius = Math.max(this.controls.minDistance, s.radius * 0.9);
    else if (e.key === '-') s.radius = Math.min(this.controls.maxDistance, s.radius / 0.9);
    else return;
    e.preventDefault();
    this.camera.position.copy(this.controls.target).add(new THREE.Vector3().setFromSpherical(s));
    this.camera.lookAt(this.controls.target);
    this.controls.update();
    this.invalidate();
  }

  /** Starts the accumulation over (the view changed) and asks for a frame. */
  invalidate() {
    this.frame = 0;
    this.request();
  }

  request() {
    if (!this.raf) this.raf = requestAnimationFrame(() => { this.raf = 0; this.draw(); });
  }

  /** The camera's inverse view-projection into m (both grounds cast their pixels' rays with it). */
  invViewProjection(m) {
    this.camera.updateMatrixWorld();
    return m.multiplyMatrices(this.camera.projectionMatrix, this.camera.matrixWorldInverse).invert();
  }

  /** What the WebGPU ground's passes take for the current camera, light and options. */
  groundParams() {
    const o = this.options, g = this.groundMaterial.uniforms;
    return {
      invViewProjection: this.invViewProjection(new THREE.Matrix4()),
      light: lightDirection(o.lightAzimuth, o.lightElevation), lightAngle: o.lightAngle, color: g.uColor.value, fade: g.uFade.value,
      sky: g.uSky.value, groundY: this.groundY, aim: this.controls.target, aoRange: 4 * this.field.radius,
      frame: this.frame, aoRays: o.aoRaysPerFrame, shadowRays: o.shadowRaysPerFrame, interpolated: o.interpolated, show: o.show,
    };
  }

  /** Draws one frame now: one more accumulation step of the ground, then the scene. */
  draw() {
    const t0 = performance.now();
    const o = this.options, light = lightDirection(o.lightAzimuth, o.lightElevation);
    if (this.gpuField) {
      const step = this.frame < o.maxFrames;
      this.gpuGround.draw(this.groundParams(), step);
      if (step) this.frame += 1;
    }
    if (!this.gpuField && this.field && this.frame < o.maxFrames) {
      const [prev, next] = this.targets;
      const u = this.accumulate.material.uniforms;
      this.invViewProjection(u.uInvViewProjection.value);
      u.uResolution.value.set(next.width, next.height);
      u.uGroundY.value = this.groundY;
      u.uFrame.value = this.frame;
      u.uPrevious.value = prev.texture;
      u.uLight.value.copy(light);
      u.uLightAngle.value = o.lightAngle;
      u.uAoRange.value = 4 * this.field.radius;
      u.uAoRays.value = o.aoRaysPerFrame;
      u.uShadowRays.value = o.shadowRaysPerFrame;
      u.uInterpolated.value = o.interpolated;
      this.accumulate.run(this.renderer, next);
      this.targets = [next, prev];
      this.frame += 1;
      const g = this.groundMaterial.uniforms;
      g.uAccumulated.value = next.texture;
      g.uShow.value = o.show;
      g.uLight.value.copy(light);
    }
    if (this.impostor) this.impostor.visible = o.show === 0;
    this.renderer.setRenderTarget(null);
    this.renderer.render(this.scene, this.camera);
    if (this.field && this.retired.length) {
      for (const m of this.retired) m.dispose();
      this.retired = [];
    }
    const ms = performance.now() - t0;
    this.onFrame({ frame: this.frame, maxFrames: o.maxFrames, ms });
    if (this.field && this.frame < o.maxFrames) this.request();
  }

  /** The deterministic reference view of the ground AO (the tests' comparison with libvff). */
  // (Through WebGPU where the ground is drawn with it: then a Promise of the same array.)
  reference(size, interpolated, api = this.backend) {
    if (!this.field) return null;
    if (api === 'webgpu' && this.gpuField) return this.gpuGround.reference(this.field.center, this.field.radius, size, interpolated);
    return referenceView(this.renderer, this.field, size, interpolated);
  }

  /** The number of drawing-buffer pixels the object covers (drawn alone on black; for the tests). */
  objectPixels() {
    if (!this.impostor) return 0;
    const keep = [this.ground.visible, this.grid.visible, this.scene.background];
    this.ground.visible = this.grid.visible = false;
    this.scene.background = new THREE.Color(0, 0, 0);
    this.renderer.setRenderTarget(null);
    this.renderer.render(this.scene, this.camera);
    const gl = this.renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    [this.ground.visible, this.grid.visible, this.scene.background] = keep;
    let n = 0;
    for (let i = 0; i < px.length; i += 4) n += px[i] + px[i + 1] + px[i + 2] > 0;
    this.invalidate();
    return n;
  }

  /** The canvas as a PNG Blob (a fresh frame drawn first; over the WebGPU ground where there is one). */
  png() {
    this.renderer.render(this.scene, this.camera);
    let out = this.canvas;
    if (this.gpuField) {
      out = document.createElement('canvas');
      [out.width, out.height] = [this.canvas.width, this.canvas.height];
      const c = out.getContext('2d');
      // A WebGPU canvas keeps its image only until it is shown: shade the ground again (no new
      // accumulation step) and copy it in the same task.
      this.gpuGround.draw(this.groundParams(), false);
      c.drawImage(this.gpuGround.canvas, 0, 0);
      c.drawImage(this.canvas, 0, 0);
    }
    return new Promise((resolve) => out.toBlob(resolve, 'image/png'));
  }
}
