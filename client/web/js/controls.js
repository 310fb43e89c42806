// Camera navigation with the conventions of three.js's OrbitControls and Blender's walk mode:
//   orbit (default)  left drag: rotate about the target · right drag or shift + left drag: pan
//                    · wheel: dolly
//   walk (F toggles) W A S D: move · Q E: down, up · drag: look · shift: faster
//   1…9: the scene's cameras · Home: the view the page started with
import { Camera } from './camera.js';
import { add, cross, dot, length, normalize, scale, sub } from './math.js';

export class Controls {
  /// Moves `camera` (a Camera, changed in place) from events on `element`; onChange() after
  /// every change. `size` is the scene's diagonal (metres), which sets speeds.
  constructor(element, camera, size, onChange) {
    this.element = element;
    this.camera = camera;
    this.start = new Camera([...camera.eye], [...camera.target], [...camera.up], camera.fovyDegrees);
    this.size = size;
    this.onChange = onChange;
    this.mode = 'orbit';
    this.keys = new Set();
    this.sceneCameras = [];
    this.enabled = true;
    element.addEventListener('contextmenu', (e) => e.preventDefault());
    element.addEventListener('pointerdown', (e) => this.down(e));
    element.addEventListener('pointermove', (e) => this.move(e));
    element.addEventListener('pointerup', (e) => this.up(e));
    element.addEventListener('wheel', (e) => this.wheel(e), { passive: false });
    addEventListener('keydown', (e) => this.key(e, true));
    addEventListener('keyup', (e) => this.key(e, false));
    this.lastTick = performance.now();
  }

  /// Puts the camera at `view` (a Camera).
  set(view) {
    const c = this.camera;
    c.eye = [...view.eye];
    c.target = [...view.target];
    c.up = [...view.up];
    c.fovyDegrees = view.fovyDegrees;
    this.onChange();
  }

  down(e) {
    if (!this.enabled) return;
    this.drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey || e.button === 1 };
    this.element.setPointerCapture(e.pointerId);
  }

  up(e) {
    this.drag = null;
    if (this.element.hasPointerCapture(e.pointerId)) this.element.releasePointerCapture(e.pointerId);
  }

  move(e) {
    if (!this.drag) return;
    const dx = e.clientX - this.drag.x, dy = e.clientY - this.drag.y;
    this.drag.x = e.clientX;
    this.drag.y = e.clientY;
    const c = this.camera;
    const { right, up } = c.basis();
    const height = this.element.clientHeight || 1;
    if (this.mode === 'walk' || !this.drag.pan) {
      // Rotation: 2π per element height, as OrbitControls; walk mode turns the view in place.
      const yaw = -2 * Math.PI * dx / height, pitch = -2 * Math.PI * dy / height;
      const pivot = this.mode === 'walk' ? c.eye : c.target;
      const offset = this.mode === 'walk' ? sub(c.target, c.eye) : sub(c.eye, c.target);
      let o = rotate(offset, [0, 1, 0], yaw);
      const side = normalize(cross(o, [0, 1, 0]));
      const pitched = rotate(o, side, this.mode === 'walk' ? pitch : -pitch);
      // Keep away from the poles, where up and the view would align.
      if (Math.abs(dot(normalize(pitched), [0, 1, 0])) < 0.995) o = pitched;
      if (this.mode === 'walk') c.target = add(pivot, o);
      else c.eye = add(pivot, o);
      c.up = [0, 1, 0];
    } else {
      // Pan: the target moves with the pointer in its own depth.
      const distance = length(sub(c.target, c.eye));
      const perPixel = 2 * distance * Math.tan(c.fovyDegrees * Math.PI / 360) / height;
      const shift = add(scale(right, -dx * perPixel), scale(up, dy * perPixel));
      c.eye = add(c.eye, shift);
      c.target = add(c.target, shift);
    }
    this.onChange();
  }

  wheel(e) {
    if (!this.enabled) return;
    e.preventDefault();
    const c = this.camera;
    const offset = sub(c.eye, c.target);
    const factor = Math.pow(0.95, -Math.sign(e.deltaY));
    if (this.mode === 'walk') {
      const step = scale(normalize(sub(c.target, c.eye)), -Math.sign(e.deltaY) * 0.02 * this.size);
      c.eye = add(c.eye, step);
      c.target = add(c.target, step);
    } else if (length(offset) * factor > 1e-3 * this.size) {
      c.eye = add(c.target, scale(offset, factor));
    }
    this.onChange();
  }

  key(e, pressed) {
    if (!this.enabled || e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    const k = e.key.toLowerCase();
    if (pressed && k === 'f') {
      this.mode = this.mode === 'walk' ? 'orbit' : 'walk';
      this.onChange();
    } else if (pressed && e.key === 'Home') {
      this.set(this.start);
    } else if (pressed && /^[1-9]$/.test(e.key) && this.sceneCameras[Number(e.key) - 1]) {
      this.set(this.sceneCameras[Number(e.key) - 1]);
    }
    if ('wasdqe'.includes(k) && k.length === 1) {
      if (pressed) this.keys.add(k);
      else this.keys.delete(k);
      // Walking starts the page's frames; tick() keeps them coming while a key is held.
      if (pressed && this.mode === 'walk') {
        this.lastTick = performance.now();
        this.onChange();
      }
    }
    this.shift = e.shiftKey;
  }

  /// Walk mode's movement for the keys held since the last call; true when the camera moved.
  tick(now) {
    const dt = Math.min(0.1, (now - this.lastTick) / 1000);
    this.lastTick = now;
    if (this.mode !== 'walk' || this.keys.size === 0) return false;
    const c = this.camera;
    const { forward, right } = c.basis();
    const speed = 0.15 * this.size * dt * (this.shift ? 4 : 1);
    let step = [0, 0, 0];
    const along = (v, s) => { step = add(step, scale(v, s)); };
    if (this.keys.has('w')) along(forward, speed);
    if (this.keys.has('s')) along(forward, -speed);
    if (this.keys.has('d')) along(right, speed);
    if (this.keys.has('a')) along(right, -speed);
    if (this.keys.has('e')) along([0, 1, 0], speed);
    if (this.keys.has('q')) along([0, 1, 0], -speed);
    c.eye = add(c.eye, step);
    c.target = add(c.target, step);
    this.onChange();
    return true;
  }
}

/// v rotated by `angle` radians about the unit axis (Rodrigues).
function rotate(v, axis, angle) {
  const cos = Math.cos(angle), sin = Math.sin(angle);
  return add(add(scale(v, cos), scale(cross(axis, v), sin)), scale(axis, dot(axis, v) * (1 - cos)));
}
