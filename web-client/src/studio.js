// The studio the product is shown in: a procedural environment light and a
// ground contact shadow, both cheap enough for a software renderer.
//
// Environment: a studio evaluated in the vertex shader (for both faces),
// not a cube map — a floor
// darker than the walls, walls brightening towards a white ceiling, a large
// key softbox overhead in front, a strip light behind for a rim. The shaded
// parts' materials add its diffuse light and its reflection (blurred by the
// material's roughness, each softbox's edge widened and its brightness
// spread accordingly) to what the lights give, in three's own lighting code
// (the irradiance and radiance it takes from an environment map). Nothing is
// precomputed: no PMREM, no render at load. The analysis materials
// (curvature, zebra, deviation) do not take it, so their colours mean what
// their legends say.
//
// Contact shadow: the model seen from below by an orthographic camera into a
// small render target, each fragment black with an opacity that fades with
// its height above the ground, blurred three times, laid on a plane under the
// model. It is redrawn only when the shape or its bounds change (at most
// every SHADOW_INTERVAL ms), drawn in the shaded view only. It is first drawn
// a few frames after the model is (SHADOW_FIRST_FRAME): its shader programs
// (four, on a software renderer about half a second to compile) must not
// hold up the customer's first picture.

import * as THREE from 'three';

/** The shadow map's size (px): the footprint's detail is far below the blur's width. */
const SHADOW_SIZE = 128;
/** The studio's brightness: it adds to the scene's lights (hemisphere and sun), which the analysis views keep. */
const STUDIO_INTENSITY = 0.5;
/** How much of the studio's light reaches a surface diffusely (the rest is its reflection). */
const STUDIO_DIFFUSE = 0.35;
/** Redraw the shadow at most this often while the shape moves (ms). */
const SHADOW_INTERVAL = 200;
/** The first shadow is drawn on this frame of the model's being shown, not on the first: the picture comes first. */
const SHADOW_FIRST_FRAME = 3;
/** How far beyond the footprint the shadow plane reaches, as a fraction of the footprint's larger side. */
const MARGIN = 0.25;
/** The faint shade under the whole shape reaches this many times the contact darkness's height. */
const SOFT_REACH = 6;

/** The colours of the studio's floor, walls and ceiling (linear). */
const FLOOR = [0.1, 0.1, 0.11];
const WALL = [0.42, 0.43, 0.46];
const CEILING = [0.75, 0.76, 0.78];
/** The softboxes: angular radius (rad) and brightness. */
const KEY = { size: 0.45, gain: 1.6 };
const RIM = { size: 0.3, gain: 0.9 };

/**
 * A softbox seen by a material of roughness r: its edge (the cosines
 * between which it fades in, widened by roughness) and its brightness
 * (spread over the wider disc, so its energy stays about the same).
 */
export function softbox({ size, gain }, r) {
  const w = size + 0.55 * r * r + 0.02;
  return [Math.cos(size + w), Math.cos(Math.max(size - w, 0)), (gain * 2 * size * size) / (w * w + size * size)];
}

const vec3 = (c) => `vec3( ${c.map((x) => x.toFixed(3)).join(', ')} )`;

/**
 * GLSL (vertex shader): the studio's radiance in direction d (view space,
 * like the studio's axes, which View.render sets each frame). key and rim
 * are softbox() for the roughness wanted, fl the floor-to-wall edge. The
 * studio is evaluated per vertex, for both faces (the parts are two-sided):
 * its light varies slowly over the surface (broad softboxes, blurred by
 * roughness), so the fragments only pick up the interpolated values — a
 * software renderer pays for it per vertex, not per pixel.
 */
const studioVertexGlsl = /* glsl */ `
uniform vec3 studioUp;
uniform vec3 studioKey;
uniform vec3 studioRim;
uniform float studioIntensity;
uniform vec3 studioKeyS;
uniform vec3 studioRimS;
uniform vec2 studioFloorS;
uniform vec3 studioKeyD;
uniform vec3 studioRimD;
uniform vec2 studioFloorD;
uniform float studioR2;
varying vec3 vStudioFront;
varying vec3 vStudioBack;
varying vec3 vStudioFrontD;
varying vec3 vStudioBackD;
vec3 studioRadiance( vec3 d, vec3 key, vec3 rim, vec2 fl ) {
  float h = dot( d, studioUp );
  vec3 base = mix( ${vec3(FLOOR)}, ${vec3(WALL)}, smoothstep( fl.x, fl.y, h ) );
  base = mix( base, ${vec3(CEILING)}, smoothstep( 0.4, 1.0, h ) );
  float boxes = smoothstep( key.x, key.y, dot( d, studioKey ) ) * key.z + smoothstep( rim.x, rim.y, dot( d, studioRim ) ) * rim.z;
  return ( base + vec3( boxes ) ) * studioIntensity;
}
vec3 studioReflected( vec3 n, vec3 v ) {
  return studioRadiance( normalize( mix( reflect( - v, n ), n, studioR2 ) ), studioKeyS, studioRimS, studioFloorS );
}
`;

/** GLSL at the end of the vertex shader: the studio's light for both faces. */
const studioVertexMain = /* glsl */ `
#include <project_vertex>
{
  vec3 sn = normalize( transformedNormal );
  vec3 sv = normalize( - mvPosition.xyz );
  vStudioFront = studioReflected( sn, sv );
  vStudioBack = studioReflected( - sn, sv );
  vStudioFrontD = ${STUDIO_DIFFUSE.toFixed(3)} * PI * studioRadiance( sn, studioKeyD, studioRimD, studioFloorD );
  vStudioBackD = ${STUDIO_DIFFUSE.toFixed(3)} * PI * studioRadiance( - sn, studioKeyD, studioRimD, studioFloorD );
}
`;

/** GLSL inserted after three's environment-map lighting: the studio's diffuse light and reflection. */
const studioLighting = /* glsl */ `
#include <lights_fragment_maps>
#if defined( RE_IndirectSpecular )
  iblIrradiance += gl_FrontFacing ? vStudioFrontD : vStudioBackD;
  radiance += gl_FrontFacing ? vStudioFront : vStudioBack;
#endif
`;

const depthVertex = /* glsl */ `
varying float vHeight;
uniform float shadowBottom;
uniform float shadowReach;
void main() {
  vec4 world = modelMatrix * vec4( position, 1.0 );
  vHeight = ( world.z - shadowBottom ) / shadowReach;
  gl_Position = projectionMatrix * viewMatrix * world;
}`;
const depthFragment = /* glsl */ `
varying float vHeight;
uniform float darkness;
void main() {
  // Dark where the shape touches the ground, and a faint shade under all of it that fades over SOFT_REACH.
  float near = clamp( 1.0 - vHeight, 0.0, 1.0 );
  float soft = 0.35 * clamp( 1.0 - vHeight / ${SOFT_REACH.toFixed(1)}, 0.0, 1.0 );
  gl_FragColor = vec4( 0.0, 0.0, 0.0, max( near * near, soft ) * darkness );
}`;
const blurVertex = /* glsl */ `
varying vec2 vUv;
void main() {
  vUv = uv;
  gl_Position = vec4( position.xy, 0.0, 1.0 );
}`;
const blurFragment = /* glsl */ `
uniform sampler2D map;
uniform vec2 step;
varying vec2 vUv;
void main() {
  vec4 s = texture2D( map, vUv ) * 0.2270270270;
  s += texture2D( map, vUv + step * 1.3846153846 ) * 0.3162162162;
  s += texture2D( map, vUv - step * 1.3846153846 ) * 0.3162162162;
  s += texture2D( map, vUv + step * 3.2307692308 ) * 0.0702702703;
  s += texture2D( map, vUv - step * 3.2307692308 ) * 0.0702702703;
  gl_FragColor = s;
}`;

/** The studio's environment light, added to materials by `light(material)`. */
export class StudioEnvironment {
  constructor() {
    /** The studio's axes in the world (z up on a screen, y up in VR) and, each frame, in the camera's view space. */
    this.world = { up: new THREE.Vector3(), key: new THREE.Vector3(), rim: new THREE.Vector3() };
    this.uniforms = {
      studioUp: { value: new THREE.Vector3() },
      studioKey: { value: new THREE.Vector3() },
      studioRim: { value: new THREE.Vector3() },
      studioIntensity: { value: STUDIO_INTENSITY },
    };
    this.setUp(new THREE.Vector3(0, 0, 1), new THREE.Vector3(0, -1, 0));
    /** The materials lit by it. */
    this.materials = new Set();
  }

  /** Orients the studio: `up` the ceiling's direction, `front` towards the viewer (world). */
  setUp(up, front) {
    const u = up.clone().normalize();
    const f = front.clone().projectOnPlane(u).normalize();
    this.world.up.copy(u);
    // The key softbox high in front of the product, the rim strip low behind it.
    this.world.key.copy(u).multiplyScalar(0.8).addScaledVector(f, 0.5).normalize();
    this.world.rim.copy(u).multiplyScalar(0.35).addScaledVector(f, -0.9).normalize();
  }

  /** Before a frame seen by `camera`: the studio's axes in its view space. */
  view(camera) {
    const m = camera.matrixWorldInverse;
    this.uniforms.studioUp.value.copy(this.world.up).transformDirection(m);
    this.uniforms.studioKey.value.copy(this.world.key).transformDirection(m);
    this.uniforms.studioRim.value.copy(this.world.rim).transformDirection(m);
  }

  /** Makes `material` (a MeshStandardMaterial; its roughness as when first drawn) take the studio's light; returns it. */
  light(material) {
    material.onBeforeCompile = (shader) => {
      const r = material.roughness;
      const v3 = (a) => ({ value: new THREE.Vector3(...a) });
      Object.assign(shader.uniforms, this.uniforms, {
        studioKeyS: v3(softbox(KEY, r)),
        studioRimS: v3(softbox(RIM, r)),
        studioFloorS: { value: new THREE.Vector2(-0.35 - 0.3 * r, 0.05 + 0.3 * r) },
        studioKeyD: v3(softbox(KEY, 1)),
        studioRimD: v3(softbox(RIM, 1)),
        studioFloorD: { value: new THREE.Vector2(-0.65, 0.35) },
        studioR2: { value: r * r },
      });
      shader.vertexShader = shader.vertexShader.replace('#include <common>', `#include <common>\n${studioVertexGlsl}`).replace('#include <project_vertex>', studioVertexMain);
      shader.fragmentShader = shader.fragmentShader
        .replace('#include <common>', '#include <common>\nvarying vec3 vStudioFront;\nvarying vec3 vStudioBack;\nvarying vec3 vStudioFrontD;\nvarying vec3 vStudioBackD;')
        .replace('#include <lights_fragment_maps>', studioLighting);
    };
    material.customProgramCacheKey = () => 'vsculpt-studio';
    material.userData.studio = true;
    material.needsUpdate = true;
    this.materials.add(material);
    return material;
  }
}

/** A soft shadow on the ground under the model, from its shape seen from below. */
export class ContactShadow {
  /**
   * @param {THREE.WebGLRenderer} renderer
   * @param {THREE.Object3D} model what casts the shadow and carries the ground (model units, z up)
   */
  constructor(renderer, model) {
    this.renderer = renderer;
    this.model = model;
    const target = () => new THREE.WebGLRenderTarget(SHADOW_SIZE, SHADOW_SIZE, { depthBuffer: true });
    this.target = target();
    this.blurred = target();
    this.target.texture.generateMipmaps = false;
    this.blurred.texture.generateMipmaps = false;
    // The camera below the ground looks up (+z); its image has x reversed, which the texture undoes.
    this.blurred.texture.repeat.set(-1, 1);
    this.blurred.texture.offset.set(1, 0);
    this.camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
    this.camera.up.set(0, 1, 0);
    this.depth = new THREE.ShaderMaterial({
      uniforms: { shadowBottom: { value: 0 }, shadowReach: { value: 1 }, darkness: { value: 0.9 } },
      vertexShader: depthVertex,
      fragmentShader: depthFragment,
      side: THREE.DoubleSide,
      transparent: true,
      blending: THREE.CustomBlending,
      blendEquation: THREE.MaxEquation,
    });
    this.blur = new THREE.ShaderMaterial({ uniforms: { map: { value: null }, step: { value: new THREE.Vector2() } }, vertexShader: blurVertex, fragmentShader: blurFragment, depthTest: false, depthWrite: false });
    this.quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), this.blur);
    this.quad.frustumCulled = false;
    this.quadCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
    this.ground = new THREE.Mesh(
      new THREE.PlaneGeometry(1, 1),
      new THREE.MeshBasicMaterial({ map: this.blurred.texture, transparent: true, depthWrite: false, color: 0x000000, polygonOffset: true, polygonOffsetFactor: 1 }),
    );
    // Black where the texture is opaque: the map's alpha is the darkness.
    this.ground.material.onBeforeCompile = (shader) => {
      shader.fragmentShader = shader.fragmentShader.replace('#include <map_fragment>', 'diffuseColor.a *= texture2D( map, vMapUv ).a;');
    };
    this.ground.name = 'contact-shadow';
    this.ground.renderOrder = -1;
    this.ground.visible = false;
    this.ground.raycast = () => {};
    model.add(this.ground);
    this.enabled = false;
    this.dirty = true;
    this.lastDrawn = -Infinity;
    this.box = new THREE.Box3();
    /** Frames so far in which the shadow could be shown (the first ones go without it). */
    this.framesShown = 0;
    /** How many times the shadow was drawn. */
    this.draws = 0;
  }

  /** The shape changed: redraw soon. */
  invalidate() {
    this.dirty = true;
  }

  /** Before each frame: shows the shadow under `box` (model units) when enabled, redrawing it when due. */
  update(box, now = performance.now()) {
    const show = this.enabled && !!box && !box.isEmpty();
    this.ground.visible = show;
    if (!show) return;
    if (++this.framesShown < SHADOW_FIRST_FRAME) {
      this.ground.visible = false;
      return;
    }
    if (!this.box.equals(box)) this.dirty = true;
    if (!this.dirty || now - this.lastDrawn < SHADOW_INTERVAL) return;
    this.box.copy(box);
    this.draw();
    this.dirty = false;
    this.lastDrawn = now;
  }

  draw() {
    const b = this.box;
    const size = b.getSize(new THREE.Vector3());
    const centre = b.getCenter(new THREE.Vector3());
    const half = (Math.max(size.x, size.y) * (1 + 2 * MARGIN)) / 2 || 1;
    const reach = Math.max(size.z, half * 0.2) * 0.5;
    const eps = half * 1e-3;
    // The ground just under the model's lowest point.
    this.ground.position.set(centre.x, centre.y, b.min.z - eps);
    this.ground.scale.set(2 * half, 2 * half, 1);
    this.ground.updateMatrixWorld(true);
    const cam = this.camera;
    cam.left = -half;
    cam.right = half;
    cam.top = half;
    cam.bottom = -half;
    cam.near = 0;
    cam.far = SOFT_REACH * reach + 2 * eps;
    cam.position.set(centre.x, centre.y, b.min.z - 2 * eps);
    cam.lookAt(centre.x, centre.y, b.max.z);
    cam.updateProjectionMatrix();
    // The model drawn in its own units: its placement (VR) is set aside meanwhile.
    const m = this.model;
    const saved = { p: m.position.clone(), q: m.quaternion.clone(), s: m.scale.clone(), parent: m.parent };
    m.position.set(0, 0, 0);
    m.quaternion.identity();
    m.scale.setScalar(1);
    m.updateMatrixWorld(true);
    this.ground.visible = false;
    this.depth.uniforms.shadowBottom.value = b.min.z;
    this.depth.uniforms.shadowReach.value = reach;
    const r = this.renderer;
    const was = { target: r.getRenderTarget(), xr: r.xr.enabled, clear: r.getClearColor(new THREE.Color()), alpha: r.getClearAlpha(), autoClear: r.autoClear };
    r.xr.enabled = false;
    r.autoClear = true;
    r.setClearColor(0x000000, 0);
    const hidden = [];
    m.traverse((o) => {
      // Only the solid drawings cast: lines, labels and sprites do not.
      if (o.visible && (o.isLine || o.isPoints || o.isSprite)) {
        o.visible = false;
        hidden.push(o);
      }
    });
    const scene = new THREE.Scene();
    scene.overrideMaterial = this.depth;
    if (saved.parent) saved.parent.remove(m);
    scene.add(m);
    r.setRenderTarget(this.target);
    r.render(scene, cam);
    scene.remove(m);
    if (saved.parent) saved.parent.add(m);
    for (const o of hidden) o.visible = true;
    // Blur across, then along.
    this.blur.uniforms.map.value = this.target.texture;
    this.blur.uniforms.step.value.set(2 / SHADOW_SIZE, 0);
    r.setRenderTarget(this.blurred);
    r.render(this.quad, this.quadCamera);
    this.blur.uniforms.map.value = this.blurred.texture;
    this.blur.uniforms.step.value.set(0, 2 / SHADOW_SIZE);
    r.setRenderTarget(this.target);
    r.render(this.quad, this.quadCamera);
    this.blur.uniforms.map.value = this.target.texture;
    this.blur.uniforms.step.value.set(2 / SHADOW_SIZE, 2 / SHADOW_SIZE);
    r.setRenderTarget(this.blurred);
    r.render(this.quad, this.quadCamera);
    r.setRenderTarget(was.target);
    r.setClearColor(was.clear, was.alpha);
    r.autoClear = was.autoClear;
    r.xr.enabled = was.xr;
    m.position.copy(saved.p);
    m.quaternion.copy(saved.q);
    m.scale.copy(saved.s);
    m.updateMatrixWorld(true);
    this.ground.visible = true;
    this.draws++;
  }
}
