// The thin client's renderer in WebGL2 (render/renderer.h's, pass for pass): shadow maps of the
// frame's lights, per subsample a G-buffer and a shading pass adding to the pixel's sum, then
// the mean, exposure and sRGB encoding of core/image.cpp onto the canvas.
import { gbufferView, subsampleOffset } from './camera.js';
import { glDepthFromZo } from './math.js';
import { layoutShadows } from './shadows.js';
import { writeLightRecord } from './lights.js';
import * as glsl from './shaders.js';

const kDataWidth = glsl.kDataWidth;

function compile(gl, type, source, name) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS))
    throw new Error(`shader ${name}: ${gl.getShaderInfoLog(shader)}`);
  return shader;
}

function program(gl, vertex, fragment, name, attributes = []) {
  const p = gl.createProgram();
  gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, vertex, `${name} (vertex)`));
  gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, fragment, `${name} (fragment)`));
  attributes.forEach((a, i) => gl.bindAttribLocation(p, i, a));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS))
    throw new Error(`program ${name}: ${gl.getProgramInfoLog(p)}`);
  const uniforms = {};
  const count = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
  for (let i = 0; i < count; ++i) {
    const info = gl.getActiveUniform(p, i);
    const uniformName = info.name.replace(/\[0\]$/, '');
    uniforms[uniformName] = gl.getUniformLocation(p, info.name);
  }
  return { program: p, uniforms };
}

/// Rows of a data texture holding `count` texels.
const rowsFor = (count) => Math.max(1, Math.ceil(count / kDataWidth));

/// A data texture: `components` values per texel, element i at (i mod width, i / width).
function dataTexture(gl, format, data, components) {
  const [internal, external, type, Array_] = {
    rgba32ui: [gl.RGBA32UI, gl.RGBA_INTEGER, gl.UNSIGNED_INT, Uint32Array],
    r32ui: [gl.R32UI, gl.RED_INTEGER, gl.UNSIGNED_INT, Uint32Array],
    rgba32f: [gl.RGBA32F, gl.RGBA, gl.FLOAT, Float32Array],
    r32f: [gl.R32F, gl.RED, gl.FLOAT, Float32Array],
  }[format];
  const texels = data.length / components;
  const rows = rowsFor(texels);
  const width = rows > 1 ? kDataWidth : Math.max(1, texels);
  const padded = new Array_(width * rows * components);
  padded.set(data);
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, texture);
  gl.texImage2D(gl.TEXTURE_2D, 0, internal, width, rows, 0, external, type, padded);
  for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
  return texture;
}

function target(gl, width, height, internal, format, type) {
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, texture);
  gl.texStorage2D(gl.TEXTURE_2D, 1, internal, width, height);
  for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
  return texture;
}

export class Renderer {
  /// WebGL2 on `canvas` for `scene` (scene.js parseScene), with the generated SH basis
  /// (shaders/gen_sh_glsl.cpp) and shadow-map layers `shadowMapSize` texels wide. Throws
  /// naming what the browser lacks.
  constructor(canvas, scene, shBasis, { shadowMapSize = 1024 } = {}) {
    const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true,
                                            alpha: false, depth: false });
    if (!gl) throw new Error('this browser has no WebGL2');
    if (!gl.getExtension('EXT_color_buffer_float'))
      throw new Error('this browser cannot render to float textures (EXT_color_buffer_float)');
    // Vulkan's 0..1 depth range, so that the G-buffer keeps the native renderer's reversed
    // depth (a −1..1 range leaves near/w a few float steps at a distance: far surfaces
    // z-fight) and shadow maps their depth.
    this.clipControl = gl.getExtension('EXT_clip_control');
    if (this.clipControl)
      this.clipControl.clipControlEXT(this.clipControl.LOWER_LEFT_EXT, this.clipControl.ZERO_TO_ONE_EXT);
    this.gl = gl;
    this.canvas = canvas;
    this.scene = scene;
    this.shadowMapSize = shadowMapSize;
    const maxSide = gl.getParameter(gl.MAX_TEXTURE_SIZE);
    if (rowsFor(scene.texels.length / 4) > maxSide)
      throw new Error(`the scene's textures need ${rowsFor(scene.texels.length / 4)} rows of ` +
                      `${kDataWidth} texels, this browser's textures hold ${maxSide}`);

    this.shadowProgram = program(gl, glsl.shadowVertex, glsl.shadowFragment, 'shadow map', ['position']);
    const attributes = ['position', 'color', 'uv0', 'uv1', 'lightmapUv'];
    this.gbufferProgram = program(gl, glsl.gbufferVertex, glsl.gbufferFragment, 'G-buffer', attributes);
    this.shadingProgram = program(gl, glsl.fullscreenVertex,
                                  glsl.shadingFragment(scene.bands_y, scene.bands_c, shBasis), 'shading');
    this.displayProgram = program(gl, glsl.fullscreenVertex, glsl.displayFragment, 'display');

    // Three unshared corners per triangle, GbufferVertex's layout (64 bytes).
    this.vertexCount = scene.vertices.length / 16;
    this.vao = gl.createVertexArray();
    gl.bindVertexArray(this.vao);
    const buffer = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    gl.bufferData(gl.ARRAY_BUFFER, scene.vertices, gl.STATIC_DRAW);
    [[3, 0], [4, 16], [2, 32], [2, 40], [2, 48]].forEach(([size, offset], i) => {
      gl.enableVertexAttribArray(i);
      gl.vertexAttribPointer(i, size, gl.FLOAT, false, 64, offset);
    });
    gl.bindVertexArray(null);

    this.data = {
      triangles: dataTexture(gl, 'rgba32ui', scene.triangles, 4),
      materials: dataTexture(gl, 'rgba32ui', scene.materialRecords, 4),
      textures: dataTexture(gl, 'rgba32ui', scene.textures, 4),
      levels: dataTexture(gl, 'rgba32ui', scene.levels, 4),
      texels: dataTexture(gl, 'rgba32f', scene.texels, 4),
      gridCaches: dataTexture(gl, 'r32ui', scene.gridCaches, 1),
      lightmapCaches: dataTexture(gl, 'r32ui', scene.lightmapCaches, 1),
      emissiveScale: null,
      lights: null,
      shadowLayers: null,
    };
    this.planes = null;
    this.shadowDepth = null;
    this.shadowLayers = 0;
    this.shadowKeys = [];
    this.size = [0, 0];
    this.lightSet = null;
  }

  /// Uploads one state's planes (FrameDecoder.planes: Uint16Array halves, coefficient-major).
  setCaches(planes) {
    const gl = this.gl;
    const caches = this.scene.caches;
    const rows = rowsFor(caches);
    const width = rows > 1 ? kDataWidth : Math.max(1, caches);
    if (!this.planes) {
      this.planes = planes.map((plane) => {
        const texture = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D_ARRAY, texture);
        gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, gl.R16F, width, rows, Math.max(1, plane.length / Math.max(caches, 1)));
        for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER])
          gl.texParameteri(gl.TEXTURE_2D_ARRAY, p, gl.NEAREST);
        return texture;
      });
      this.staging = new Uint16Array(width * rows);
    }
    planes.forEach((plane, t) => {
      gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.planes[t]);
      const layers = plane.length / Math.max(caches, 1);
      for (let k = 0; k < layers; ++k) {
        this.staging.set(plane.subarray(k * caches, (k + 1) * caches));
        gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, k, width, rows, 1, gl.RED, gl.HALF_FLOAT, this.staging);
      }
    });
  }

  /// The light set to shade with (lights.js lightSetOf): records, emissive scales and the
  /// shadow maps of the lights whose depth changed.
  setLights(lightSet) {
    const gl = this.gl;
    this.lightSet = lightSet;
    const { shadows, layers } = layoutShadows(lightSet.lights, this.scene.bounds, this.shadowMapSize);
    const records = new Uint32Array(Math.max(1, lightSet.lights.length) * 20);
    lightSet.lights.forEach((light, k) => writeLightRecord(records, k, light, shadows[k]));
    if (this.data.lights) gl.deleteTexture(this.data.lights);
    this.data.lights = dataTexture(gl, 'rgba32ui', records, 4);
    const layerRecords = new Float32Array(Math.max(1, layers.length) * 20);
    layers.forEach((layer, i) => {
      layerRecords.set(layer.clip, 20 * i);
      layerRecords[20 * i + 16] = layer.texelSlope;
      layerRecords[20 * i + 17] = layer.side;
    });
    if (this.data.shadowLayers) gl.deleteTexture(this.data.shadowLayers);
    this.data.shadowLayers = dataTexture(gl, 'rgba32f', layerRecords, 4);
    const scales = new Float32Array(Math.max(1, this.scene.materials.length));
    this.scene.materials.forEach((m, i) => {
      const s = lightSet.emissiveScale[m.name];
      scales[i] = s === undefined ? 1 : s;
    });
    if (this.data.emissiveScale) gl.deleteTexture(this.data.emissiveScale);
    this.data.emissiveScale = dataTexture(gl, 'r32f', scales, 1);

    // The depth array grows when the lights need more layers (every map is then redrawn).
    let reallocated = false;
    if (layers.length > this.shadowLayers || !this.shadowDepth) {
      if (this.shadowDepth) gl.deleteTexture(this.shadowDepth);
      this.shadowLayers = Math.max(1, layers.length);
      this.shadowDepth = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.shadowDepth);
      gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, gl.DEPTH_COMPONENT32F, this.shadowMapSize,
                      this.shadowMapSize, this.shadowLayers);
      for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER])
        gl.texParameteri(gl.TEXTURE_2D_ARRAY, p, gl.NEAREST);
      reallocated = true;
    }
    // A light keeps its maps when what its depth depends on did not change.
    const p = this.shadowProgram;
    gl.useProgram(p.program);
    gl.bindVertexArray(this.vao);
    if (!this.shadowFramebuffer) this.shadowFramebuffer = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.shadowFramebuffer);
    gl.drawBuffers([gl.NONE]);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LESS);
    gl.depthMask(true);
    gl.disable(gl.CULL_FACE);
    gl.clearDepth(1);
    this.shadowMapsRendered = 0;
    shadows.forEach((shadow, k) => {
      if (!reallocated && this.shadowKeys[k] === shadow.key) return;
      ++this.shadowMapsRendered;
      const count = k + 1 < shadows.length ? shadows[k + 1].firstLayer - shadow.firstLayer
                                           : layers.length - shadow.firstLayer;
      for (let i = 0; i < count; ++i) {
        const layer = layers[shadow.firstLayer + i];
        gl.framebufferTextureLayer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, this.shadowDepth, 0,
                                   shadow.firstLayer + i);
        gl.viewport(0, 0, layer.side, layer.side);
        gl.uniform2f(p.uniforms.viewport, layer.side, layer.side);
        gl.clear(gl.DEPTH_BUFFER_BIT);
        gl.uniformMatrix4fv(p.uniforms.clip, false,
                            this.clipControl ? layer.clip : glDepthFromZo(layer.clip));
        gl.drawArrays(gl.TRIANGLES, 0, this.vertexCount);
      }
    });
    this.shadowKeys = shadows.map((s) => s.key);
    gl.bindVertexArray(null);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }

  resize(width, height) {
    if (this.size[0] === width && this.size[1] === height) return;
    const gl = this.gl;
    this.size = [width, height];
    this.canvas.width = width;
    this.canvas.height = height;
    for (const t of this.targets || []) gl.deleteTexture(t);
    this.gbuffer = [0, 1, 2, 3].map(() => target(gl, width, height, gl.RGBA32F));
    this.depth = target(gl, width, height, gl.DEPTH_COMPONENT32F);
    this.sums = [0, 1].map(() => target(gl, width, height, gl.RGBA32F));
    this.targets = [...this.gbuffer, this.depth, ...this.sums];
    this.gbufferFramebuffer = this.gbufferFramebuffer || gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.gbufferFramebuffer);
    this.gbuffer.forEach((t, i) =>
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + i, gl.TEXTURE_2D, t, 0));
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.TEXTURE_2D, this.depth, 0);
    gl.drawBuffers([0, 1, 2, 3].map((i) => gl.COLOR_ATTACHMENT0 + i));
    this.sumFramebuffers = this.sums.map((t) => {
      const f = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, f);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, t, 0);
      return f;
    });
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }

  /// Without EXT_clip_control: a conventional depth range from a thousandth of the scene's
  /// diagonal (nearer surfaces are clipped) to past its farthest corner.
  fallbackDepth(camera) {
    const { min, max } = this.scene.bounds;
    let far = 0;
    for (let corner = 0; corner < 8; ++corner) {
      const c = [corner & 1 ? max[0] : min[0], corner & 2 ? max[1] : min[1], corner & 4 ? max[2] : min[2]];
      far = Math.max(far, Math.hypot(c[0] - camera.eye[0], c[1] - camera.eye[1], c[2] - camera.eye[2]));
    }
    const near = 1e-3 * Math.hypot(max[0] - min[0], max[1] - min[1], max[2] - min[2]);
    return { zeroToOne: false, near, far: Math.max(1.01 * far, 2 * near) };
  }

  bindTexture(unit, kind, texture, location) {
    const gl = this.gl;
    gl.activeTexture(gl.TEXTURE0 + unit);
    gl.bindTexture(kind, texture);
    gl.uniform1i(location, unit);
  }

  /// Draws `camera`'s view at width × height with `samples` subsamples per pixel and
  /// `exposure`, from the caches and lights set last.
  render(camera, width, height, { samples = 4, exposure = 1 } = {}) {
    const gl = this.gl;
    if (!this.planes || !this.lightSet) return;
    this.resize(width, height);
    const scene = this.scene;
    gl.viewport(0, 0, width, height);
    const depth = this.clipControl ? { zeroToOne: true } : this.fallbackDepth(camera);
    for (let s = 0; s < samples; ++s) {
      const view = gbufferView(camera, width, height, scene.near, subsampleOffset(s, samples),
                               1 / Math.sqrt(samples), depth);
      // G-buffer, colours cleared to 0 (a pixel nothing covers has hit flag 0).
      let p = this.gbufferProgram;
      gl.useProgram(p.program);
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.gbufferFramebuffer);
      for (let i = 0; i < 4; ++i) gl.clearBufferfv(gl.COLOR, i, [0, 0, 0, 0]);
      gl.clearDepth(depth.zeroToOne ? 0 : 1);
      gl.clear(gl.DEPTH_BUFFER_BIT);
      gl.enable(gl.DEPTH_TEST);
      gl.depthFunc(depth.zeroToOne ? gl.GREATER : gl.LESS);
      gl.depthMask(true);
      gl.disable(gl.CULL_FACE);
      gl.uniformMatrix4fv(p.uniforms.clip, false, view.clip);
      gl.uniform3fv(p.uniforms.eye, camera.eye);
      gl.uniform3fv(p.uniforms.forward, view.forward);
      gl.uniform3fv(p.uniforms.directionPerPixelX, view.directionPerPixelX);
      gl.uniform3fv(p.uniforms.directionPerPixelY, view.directionPerPixelY);
      const d = this.data;
      ['triangles', 'materials', 'textures', 'levels', 'texels', 'emissiveScale'].forEach((name, unit) =>
        this.bindTexture(unit, gl.TEXTURE_2D, d[name], p.uniforms[name]));
      gl.bindVertexArray(this.vao);
      gl.drawArrays(gl.TRIANGLES, 0, this.vertexCount);
      gl.bindVertexArray(null);
      gl.disable(gl.DEPTH_TEST);

      // Shading: this subsample's radiance added to the sum of the earlier ones.
      p = this.shadingProgram;
      gl.useProgram(p.program);
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.sumFramebuffers[s % 2]);
      const u = p.uniforms;
      const textures2d = [['gbufferPositionU', this.gbuffer[0]], ['gbufferNormalV', this.gbuffer[1]],
                          ['gbufferAlbedo', this.gbuffer[2]], ['gbufferEmission', this.gbuffer[3]],
                          ['previous', this.sums[(s + 1) % 2]], ['lights', d.lights],
                          ['shadowLayers', d.shadowLayers], ['gridCaches', d.gridCaches],
                          ['lightmapCaches', d.lightmapCaches]];
      textures2d.forEach(([name, t], unit) => this.bindTexture(unit, gl.TEXTURE_2D, t, u[name]));
      [['shadowMaps', this.shadowDepth], ['planeY', this.planes[0]], ['planeCo', this.planes[1]],
       ['planeCg', this.planes[2]]].forEach(([name, t], i) =>
        this.bindTexture(textures2d.length + i, gl.TEXTURE_2D_ARRAY, t, u[name]));
      gl.uniform1ui(u.noCache, scene.no_cache >>> 0);
      gl.uniform3fv(u.eye, camera.eye);
      gl.uniform3fv(u.gridOrigin, scene.grid.origin);
      gl.uniform1f(u.gridCellSize, scene.grid.cell_size);
      gl.uniform3iv(u.gridDims, scene.grid.dims);
      gl.uniform1i(u.lightCount, this.lightSet.lights.length);
      gl.uniform2iv(u.lightmapSize, [scene.lightmap.width, scene.lightmap.height]);
      gl.uniform1f(u.epsilon, scene.epsilon);
      gl.uniform1i(u.accumulate, s > 0 ? 1 : 0);
      gl.uniform1i(u.direct, 1);
      gl.uniform1f(u.yScale, this.lightSet.indirectScale.y);
      gl.uniform1f(u.cocgScale, this.lightSet.indirectScale.cocg);
      gl.uniform1fv(u.clampedCosine, scene.sh.clamped_cosine);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    }
    // The mean of the subsamples, exposed and encoded onto the canvas.
    const p = this.displayProgram;
    gl.useProgram(p.program);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    this.bindTexture(0, gl.TEXTURE_2D, this.sums[(samples - 1) % 2], p.uniforms.radianceSum);
    gl.uniform1f(p.uniforms.samples, samples);
    gl.uniform1f(p.uniforms.exposure, exposure);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }
}
