// `?fast`, the viewport for machines without a GPU: morph targets blended on the CPU (only the
// targets with weight, as sparse lists of the vertices they move) and lighting computed per
// vertex. The meshes keep their `morphTargetInfluences`; playback writes them as usual.

import * as THREE from 'three';
import { hemisphere, key } from './scene.js';

/** The same lights as the scene's, evaluated once per vertex instead of once per pixel: software
 * GL (SwiftShader, 2 cores) drew capture mode's view of the 49k-triangle ICT head at 12–14 frames
 * per second with three.js's Lambert material and at 16–20 with this one. The lit colour is turned to sRGB in the vertex shader
 * too, so a pixel only interpolates it (and multiplies a texture, left sRGB-encoded: gamma is a
 * power law, so encoding the product or the factors agrees). Both faces are lit: the fragment
 * picks the side it sees. */
export function vertexLitMaterial(/** @type {any} */ source) {
  const map = source.map ? source.map.clone() : null;
  if (map) { map.colorSpace = THREE.NoColorSpace; map.needsUpdate = true; }
  return new THREE.ShaderMaterial({
    vertexColors: !!source.vertexColors,
    defines: map ? { FAST_MAP: '' } : {},
    uniforms: {
      albedo: { value: (source.color || new THREE.Color(1, 1, 1)).clone() },
      map: { value: map },
      sky: { value: hemisphere.color.clone().multiplyScalar(hemisphere.intensity) },
      ground: { value: hemisphere.groundColor.clone().multiplyScalar(hemisphere.intensity) },
      keyColor: { value: key.color.clone().multiplyScalar(key.intensity) },
      keyDirection: { value: key.position.clone().sub(key.target.position).normalize() },
    },
    vertexShader: `
      uniform vec3 albedo, sky, ground, keyColor, keyDirection;
      varying vec3 litFront, litBack;
      #ifdef FAST_MAP
      varying vec2 texCoord;
      #endif
      #include <skinning_pars_vertex>
      vec3 encodeSrgb(vec3 c) {
        c = clamp(c, 0.0, 1.0);
        return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
      }
      vec3 lit(vec3 n, vec3 up, vec3 toKey, vec3 base) {
        vec3 irradiance = mix(ground, sky, 0.5 * dot(n, up) + 0.5) + keyColor * max(dot(n, toKey), 0.0);
        return encodeSrgb(base * irradiance / 3.14159265);
      }
      void main() {
        // A view skinned to the face's bones turns them here (three.js's own skinning chunks).
        vec3 objectNormal = vec3(normal);
        vec3 transformed = vec3(position);
        #include <skinbase_vertex>
        #include <skinnormal_vertex>
        #include <skinning_vertex>
        vec3 n = normalize(normalMatrix * objectNormal);
        vec3 up = normalize((viewMatrix * vec4(0.0, 1.0, 0.0, 0.0)).xyz);
        vec3 toKey = normalize((viewMatrix * vec4(keyDirection, 0.0)).xyz);
        vec3 base = albedo;
        #ifdef USE_COLOR
        base *= color.rgb;
        #endif
        litFront = lit(n, up, toKey, base);
        litBack = lit(-n, up, toKey, base);
        #ifdef FAST_MAP
        texCoord = uv;
        #endif
        gl_Position = projectionMatrix * modelViewMatrix * vec4(transformed, 1.0);
      }`,
    fragmentShader: `
      varying vec3 litFront, litBack;
      #ifdef FAST_MAP
      uniform sampler2D map;
      varying vec2 texCoord;
      #endif
      void main() {
        vec3 c = gl_FrontFacing ? litFront : litBack;
        #ifdef FAST_MAP
        c *= texture2D(map, texCoord).rgb;
        #endif
        gl_FragColor = vec4(c, 1.0);
      }`,
  });
}

/** Without a GPU, morphing 50 targets per vertex in the (software) vertex shader costs most of
 * a frame. `?fast` moves it to the CPU instead: each target is kept as the sparse list of the
 * vertices it moves, and only targets with weight are added, once per drawn frame. The mesh
 * keeps its `morphTargetInfluences` (the mixer and the layers write them as before). */
export function blendOnCpu(mesh) {
  const geometry = mesh.geometry;
  const morphs = geometry.morphAttributes.position;
  if (!morphs || !morphs.length || !geometry.morphTargetsRelative) return;
  const sparse = (attribute) => {
    if (!attribute) return null;
    const indices = [], values = [];
    for (let v = 0; v < attribute.count; v++) {
      const x = attribute.getX(v), y = attribute.getY(v), z = attribute.getZ(v);
      if (x !== 0 || y !== 0 || z !== 0) { indices.push(v); values.push(x, y, z); }
    }
    return { indices: Int32Array.from(indices), values: Float32Array.from(values) };
  };
  const normals = geometry.morphAttributes.normal || [];
  mesh.userData.cpuMorph = {
    basePosition: Float32Array.from(geometry.attributes.position.array),
    baseNormal: geometry.attributes.normal ? Float32Array.from(geometry.attributes.normal.array) : null,
    targets: morphs.map((m, i) => ({ position: sparse(m), normal: sparse(normals[i]) })),
    shown: /** @type {number[]|null} */ (null),
  };
  geometry.morphAttributes = {};
  mesh.frustumCulled = false;
}

/** Applies the CPU blend of `mesh` when its weights changed since it was last drawn. */
export function blendNow(mesh) {
  const cpu = mesh.userData.cpuMorph;
  const weights = mesh.morphTargetInfluences;
  if (!cpu || !weights) return;
  if (cpu.shown && cpu.shown.length === weights.length && cpu.shown.every((w, i) => w === weights[i])) return;
  cpu.shown = Array.from(weights);
  const add = (out, base, kind) => {
    out.set(base);
    cpu.targets.forEach((target, t) => {
      const w = weights[t], part = target[kind];
      if (!part || Math.abs(w) < 1e-4) return;
      const { indices, values } = part;
      for (let k = 0; k < indices.length; k++) {
        const o = indices[k] * 3;
        out[o] += w * values[3 * k]; out[o + 1] += w * values[3 * k + 1]; out[o + 2] += w * values[3 * k + 2];
      }
    });
  };
  const position = mesh.geometry.attributes.position;
  add(position.array, cpu.basePosition, 'position');
  position.needsUpdate = true;
  const normal = mesh.geometry.attributes.normal;
  if (normal && cpu.baseNormal) { add(normal.array, cpu.baseNormal, 'normal'); normal.needsUpdate = true; }
}
