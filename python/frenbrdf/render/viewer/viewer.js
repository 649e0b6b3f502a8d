// frenbrdf view: renders a neural BRDF live in WebGL2 (the NBRDF evaluated per pixel in the fragment shader),
// with BRDF Explorer's in-plane polar plot and θ_h × θ_d image. No network access: everything is in this page.
//
// The sphere mirrors frenbrdf.render.renderer (Scene()): an orthographic camera looking down −z at a unit
// sphere, directional lights in world space (+y up), each pixel's tangent frame built the same way, radiance
// f · L · cos θ_i summed over the lights, then exposure → clamp → gamma 2.2. The fixed lights (fill, rim, the
// environment's 48 directions) are accumulated a few per frame into a float texture; the key light, which the
// user drags, is evaluated every frame on top of it.
"use strict";

(function () {
  const MAX_REFLECTANCE = 1e8;  // frenbrdf.io.reflectance.MAX_REFLECTANCE: every NBRDF's output is clamped to it
  const SEAM = 1e-9;  // frenbrdf.models.nbrdf.SEAM (float32 turns it into ~0 on the GPU, as intended)

  const state = {};
  const view = window.frenbrdfView = {ready: false, error: null, state};

  function fail(message) {
    view.error = message;
    const box = document.getElementById("error");
    box.textContent = message;
    box.hidden = false;
    for (const id of ["canvas", "controls", "plots"]) {
      const element = document.getElementById(id);
      if (element) element.hidden = true;
    }
    document.body.dataset.state = "error";
  }

  // ---- the embedded material ---------------------------------------------------------------------------------

  function readData() {
    const element = document.getElementById("frenbrdf-data");
    if (!element) throw new Error("this page holds no material (its data block is missing)");
    let data;
    try {
      data = JSON.parse(element.textContent);
    } catch (error) {
      throw new Error("this page's material data is damaged (" + error.message + ")");
    }
    if (!data || data.format !== "frenbrdf-view" || data.version !== 1) {
      throw new Error("this page's material data is not a frenbrdf view of version 1");
    }
    const texture = data.texture;
    let bytes;
    try {
      bytes = Uint8Array.from(atob(texture.data), (c) => c.charCodeAt(0));
    } catch (error) {
      throw new Error("this page's weights are damaged (not base64)");
    }
    const expected = texture.width * texture.height * 16;
    if (bytes.length !== expected) {
      throw new Error(`this page's weights are damaged: ${bytes.length} bytes where ${expected} were expected`);
    }
    const weights = new Float32Array(bytes.buffer);
    if (!weights.every(Number.isFinite)) throw new Error("this page's weights hold NaN or inf");
    for (const net of data.networks) {
      const rows = net.widths.slice(1).reduce((sum, w) => sum + pad(w), 0);
      if (net.row < 0 || net.row + rows > texture.height || Math.ceil(Math.max(...net.widths.slice(0, -1)) / 4) + 1 > texture.width) {
        throw new Error("this page's network layout does not fit its weights");
      }
    }
    data.weights = weights;
    return data;
  }

  function pad(n) { return 4 * Math.ceil(n / 4); }

  // The terms of the material shown at edit position t: [network, weight] in the slots' order
  // (frenbrdf.render.viewer.sources.Edit.terms). Slots: keyframe, a, D(z_a), b, D(z_b).
  function slotWeights() {
    const edit = state.data.edit;
    if (!edit) return {rows: [state.data.networks[0].row], weights: [1]};
    const last = edit.keyframes.length - 1;
    const k = Math.round(state.t * last), t = k / last;
    const nets = state.data.networks;
    const rows = [nets[edit.keyframes[k]].row, nets[edit.a].row, nets[edit.keyframes[0]].row, nets[edit.b].row,
      nets[edit.keyframes[last]].row];
    let weights = [1, 0, 0, 0, 0];
    if (state.mode === "kept") {
      weights = k === 0 ? [0, 1, 0, 0, 0] : k === last ? [0, 0, 0, 1, 0] : [1, 1 - t, -(1 - t), t, -t];
    }
    return {rows, weights};
  }

  // The networks of the slots (their architecture, order input and mapping are fixed; rows change with t).
  function slotNetworks(data) {
    const edit = data.edit;
    if (!edit) return [data.networks[0]];
    const n = data.networks, last = edit.keyframes.length - 1;
    return [n[edit.keyframes[0]], n[edit.a], n[edit.keyframes[0]], n[edit.b], n[edit.keyframes[last]]];
  }

  // ---- the shader ---------------------------------------------------------------------------------------------

  const f = (x) => {
    const s = Number(x).toPrecision(9);
    return /[.eE]/.test(s) ? s : s + ".0";
  };

  // One GLSL function per slot: the MLP with its widths baked in, weights from the texture (one row per unit,
  // four inputs a texel, the biases of four units in the texel after the first of them).
  function mlpSource(net, index) {
    const widths = net.widths;
    let code = `vec3 net${index}(int base, vec4 x0, vec4 x1) {\n  vec4 a0[2] = vec4[2](x0, x1);\n`;
    let offset = 0;
    for (let l = 1; l < widths.length; l++) {
      const nin = pad(widths[l - 1]) / 4, groups = pad(widths[l]) / 4, last = l === widths.length - 1;
      code += `  vec4 a${l}[${groups}];\n  for (int j = 0; j < ${groups}; j++) {\n` +
        `    int r = base + ${offset} + 4 * j;\n    vec4 o = texelFetch(uWeights, ivec2(${nin}, r), 0);\n` +
        `    for (int k = 0; k < ${nin}; k++) {\n      vec4 v = a${l - 1}[k];\n` +
        `      o += vec4(dot(texelFetch(uWeights, ivec2(k, r), 0), v), dot(texelFetch(uWeights, ivec2(k, r + 1), 0), v),\n` +
        `                dot(texelFetch(uWeights, ivec2(k, r + 2), 0), v), dot(texelFetch(uWeights, ivec2(k, r + 3), 0), v));\n` +
        `    }\n    a${l}[j] = ${last ? "o" : "max(o, 0.0)"};\n  }\n`;
      offset += pad(widths[l]);
    }
    return code + `  return a${widths.length - 1}[0].xyz;\n}\n`;
  }

  function mappingConstants(m, name) {
    return `const vec3 ${name}R = vec3(${f(m[0])}, ${f(m[1])}, ${f(m[2])});\n` +
      `const float ${name}E = ${f(m[3])};\nconst float ${name}C = ${f(m[4])};\n`;
  }

  function brdfSource(data) {
    const nets = slotNetworks(data);
    let code = `uniform highp sampler2D uWeights;\nuniform int uRow[${nets.length}];\nuniform float uWeight[${nets.length}];\n`;
    code += mappingConstants(data.mapping, "M");
    nets.forEach((net, i) => { code += mlpSource(net, i) + mappingConstants(net.mapping, `M${i}`); });
    code += `
vec3 brdf(vec3 wi, vec3 wo) {
  // frenbrdf.models.nbrdf.nbrdf_coordinates: H rotated onto the xz-plane, D in H's frame, folded by reciprocity.
  vec3 s = wi + wo;
  vec3 h = length(s) > 1e-12 ? normalize(s) : vec3(0.0, 0.0, 1.0);
  float rho = length(h.xy);
  float ct = rho == 0.0 ? sign(h.z) : h.z, st = rho, cp = rho == 0.0 ? 1.0 : h.x / rho, sp = rho == 0.0 ? 0.0 : h.y / rho;
  float px = cp * wi.x + sp * wi.y, py = -sp * wi.x + cp * wi.y;
  vec3 d = vec3(ct * px - st * wi.z, py, st * px + ct * wi.z);
  float order = (d.y < -${f(SEAM)} || (abs(d.y) <= ${f(SEAM)} && d.x < -${f(SEAM)})) ? -1.0 : 1.0;
  if (order < 0.0) d.xy = -d.xy;
  vec4 x1 = vec4(d.yz, 0.0, 0.0);
`;
    if (nets.length === 1) {
      const o = nets[0].ordered ? "order" : "0.0";
      return code + `  vec3 y = net0(uRow[0], vec4(rho, ${o}, h.z, d.x), x1);
  return clamp((M0R + M0E) * (exp(y) - M0C) - M0E, 0.0, ${f(MAX_REFLECTANCE)});
}
`;
    }
    code += "  vec3 y = vec3(0.0);\n";
    nets.forEach((net, i) => {
      const o = net.ordered ? "order" : "0.0";
      code += `  if (uWeight[${i}] != 0.0) {
    vec3 f${i} = clamp((M${i}R + M${i}E) * (exp(net${i}(uRow[${i}], vec4(rho, ${o}, h.z, d.x), x1)) - M${i}C) - M${i}E, 0.0, ${f(MAX_REFLECTANCE)});
    y += uWeight[${i}] * log(MC + (f${i} + ME) / (MR + ME));
  }
`;
    });
    return code + `  return clamp((MR + ME) * (exp(y) - MC) - ME, 0.0, ${f(MAX_REFLECTANCE)});\n}\n`;
  }

  const SURFACE = `
uniform int uShape;  // 0: the metric renderer's sphere; 1: a plane seen in perspective
uniform float uSize;
// The shaded point under this pixel: its normal and view direction (world space), as the renderer builds them.
bool surface(out vec3 n, out vec3 v) {
  vec2 p = gl_FragCoord.xy / uSize * 2.0 - 1.0;  // image row 0 at the top: gl_FragCoord.y runs up
  if (uShape == 0) {
    float r2 = dot(p, p);
    if (r2 >= 1.0) return false;
    n = vec3(p, sqrt(1.0 - r2));
    v = vec3(0.0, 0.0, 1.0);  // orthographic, looking down −z
    return true;
  }
  vec3 eye = vec3(0.0, 0.0, 3.0), ray = normalize(vec3(p * 0.5, -1.0));
  n = normalize(vec3(0.0, 1.0, 0.55));
  float t = -dot(eye, n) / dot(ray, n);
  vec3 q = eye + t * ray;
  vec3 u = normalize(cross(n, vec3(1.0, 0.0, 0.0)));
  if (t <= 0.0 || abs(q.x) > 1.3 || abs(dot(q, u)) > 1.3) return false;
  v = -ray;
  return true;
}
// The BRDF term of one light at a shaded point, in the pixel's tangent frame (renderer._tile_geometry).
vec3 shade(vec3 n, vec3 v, vec3 light, vec3 radiance) {
  vec3 helper = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  vec3 t = normalize(cross(helper, n)), b = cross(n, t);
  vec3 wi = vec3(dot(t, light), dot(b, light), dot(n, light));
  vec3 wo = vec3(dot(t, v), dot(b, v), dot(n, v));
  if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);
  return brdf(wi, wo) * radiance * wi.z;
}
`;

  const ACCUMULATE = `
uniform highp sampler2D uPrevious;
uniform vec4 uLights[2 * 64];  // direction, radiance × solid angle
uniform int uStart, uCount;
out vec4 colour;
void main() {
  vec3 sum = texelFetch(uPrevious, ivec2(gl_FragCoord.xy), 0).rgb;
  vec3 n, v;
  if (surface(n, v)) {
    for (int i = uStart; i < uStart + uCount; i++) sum += shade(n, v, normalize(uLights[2 * i].xyz), uLights[2 * i + 1].rgb);
  }
  colour = vec4(sum, 1.0);
}
`;

  const COMPOSITE = `
uniform highp sampler2D uStatic;
uniform vec3 uKey, uKeyRadiance;
uniform float uExposure;
out vec4 colour;
void main() {
  vec3 sum = texelFetch(uStatic, ivec2(gl_FragCoord.xy), 0).rgb;
  vec3 n, v;
  if (surface(n, v) && uKeyRadiance != vec3(0.0)) sum += shade(n, v, uKey, uKeyRadiance);
  colour = vec4(pow(clamp(sum * uExposure, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);  // renderer.tonemap
}
`;

  const VERTEX = `#version 300 es
void main() {
  vec2 corner = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(corner, 0.0, 1.0);
}
`;

  function program(gl, fragment) {
    const compile = (type, source) => {
      const shader = gl.createShader(type);
      gl.shaderSource(shader, source);
      gl.compileShader(shader);
      if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
        throw new Error("the shader does not compile here: " + gl.getShaderInfoLog(shader));
      }
      return shader;
    };
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl.VERTEX_SHADER, VERTEX));
    gl.attachShader(p, compile(gl.FRAGMENT_SHADER, fragment));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error("the shader does not link here: " + gl.getProgramInfoLog(p));
    const uniforms = {};
    const count = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < count; i++) {
      const name = gl.getActiveUniform(p, i).name.replace(/\[0\]$/, "");
      uniforms[name] = gl.getUniformLocation(p, name);
    }
    return {program: p, uniforms};
  }

  // ---- the renderer -------------------------------------------------------------------------------------------

  function setupGL(canvas, data) {
    const gl = canvas.getContext("webgl2", {preserveDrawingBuffer: true, antialias: false});
    if (!gl) throw new Error("this browser has no WebGL2, which the viewer needs to render the material");
    if (!gl.getExtension("EXT_color_buffer_float")) throw new Error("this browser's WebGL2 cannot render to float textures (EXT_color_buffer_float), which the viewer needs");
    const header = "#version 300 es\nprecision highp float;\nprecision highp int;\n" + brdfSource(data) + SURFACE;
    const g = {gl, accumulate: program(gl, header + ACCUMULATE), composite: program(gl, header + COMPOSITE)};
    g.weights = gl.createTexture();
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, g.weights);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, data.texture.width, data.texture.height, 0, gl.RGBA, gl.FLOAT, data.weights);
    for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
    g.vao = gl.createVertexArray();
    return g;
  }

  function targets(g, size) {
    const gl = g.gl;
    if (g.size === size) return;
    g.size = size;
    g.targets = [0, 1].map(() => {
      const texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, size, size, 0, gl.RGBA, gl.FLOAT, null);
      for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
      const framebuffer = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, texture, 0);
      if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE) throw new Error("this browser cannot render to a float texture");
      return {texture, framebuffer};
    });
  }

  function bindCommon(g, p) {
    const gl = g.gl, u = p.uniforms, slots = slotWeights();
    gl.useProgram(p.program);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, g.weights);
    gl.uniform1i(u.uWeights, 0);
    gl.uniform1iv(u.uRow, slots.rows);
    gl.uniform1fv(u.uWeight, slots.weights);
    gl.uniform1i(u.uShape, state.shape === "plane" ? 1 : 0);
    gl.uniform1f(u.uSize, g.size);
  }

  // The fixed lights of the current settings: fill and rim, then the environment's directions.
  function staticLights() {
    const lights = state.data.lights;
    return [...(state.fill ? lights.fixed : []), ...(state.env ? lights.environment : [])];
  }

  // Adds the next few fixed lights into the accumulation texture; returns whether any were left.
  function accumulate(g) {
    const gl = g.gl, lights = staticLights();
    const first = g.done, count = Math.min(state.chunk, lights.length - first);
    const source = g.targets[g.current], target = g.targets[1 - g.current];
    gl.bindFramebuffer(gl.FRAMEBUFFER, target.framebuffer);
    gl.viewport(0, 0, g.size, g.size);
    if (first === 0) {  // start afresh from zero
      gl.clearColor(0, 0, 0, 0);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.bindFramebuffer(gl.FRAMEBUFFER, source.framebuffer);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.bindFramebuffer(gl.FRAMEBUFFER, target.framebuffer);
    }
    if (count <= 0) return false;
    const p = g.accumulate, u = p.uniforms;
    bindCommon(g, p);
    const packed = new Float32Array(2 * 64 * 4);
    lights.slice(first, first + count).forEach(([direction, radiance], i) => {
      packed.set([...direction, 0, ...radiance, 0], 8 * i);
    });
    gl.uniform4fv(u.uLights, packed);
    gl.uniform1i(u.uStart, 0);
    gl.uniform1i(u.uCount, count);
    gl.activeTexture(gl.TEXTURE1);
    gl.bindTexture(gl.TEXTURE_2D, source.texture);
    gl.uniform1i(u.uPrevious, 1);
    gl.bindVertexArray(g.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    g.current = 1 - g.current;
    g.done += count;
    return true;
  }

  function composite(g) {
    const gl = g.gl, p = g.composite, u = p.uniforms;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, g.size, g.size);
    bindCommon(g, p);
    gl.activeTexture(gl.TEXTURE1);
    gl.bindTexture(gl.TEXTURE_2D, g.targets[g.current].texture);
    gl.uniform1i(u.uStatic, 1);
    gl.uniform3fv(u.uKey, direction(state.light));
    gl.uniform3fv(u.uKeyRadiance, state.key ? state.data.lights.key.radiance : [0, 0, 0]);
    gl.uniform1f(u.uExposure, state.exposure);
    gl.bindVertexArray(g.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // (θ, φ) in degrees → the direction towards the light: θ from the camera axis +z, φ from +x (right) towards +y (up).
  function direction([theta, phi]) {
    const t = theta * Math.PI / 180, p = phi * Math.PI / 180;
    return [Math.sin(t) * Math.cos(p), Math.sin(t) * Math.sin(p), Math.cos(t)];
  }

  // ---- the NBRDF on the CPU, for the plots (the same arithmetic as the shader, in float64) --------------------

  function evalNet(net, x) {
    const w = state.data.weights, width = state.data.texture.width;
    let a = x, row = net.row;
    for (let l = 1; l < net.widths.length; l++) {
      const nin = net.widths[l - 1], nout = net.widths[l], groups = pad(nin) / 4, out = new Float64Array(nout);
      for (let j = 0; j < nout; j++) {
        const r = row + j, base = 4 * (r * width);
        let s = w[4 * ((row + 4 * Math.floor(j / 4)) * width + groups) + (j % 4)];
        for (let k = 0; k < nin; k++) s += w[base + k] * a[k];
        out[j] = l < net.widths.length - 1 ? Math.max(s, 0) : s;
      }
      a = out;
      row += pad(nout);
    }
    return a;
  }

  function fromMapped(m, y) {
    return Array.from(y, (v, c) => Math.min(Math.max((m[c] + m[3]) * (Math.exp(v) - m[4]) - m[3], 0), MAX_REFLECTANCE));
  }

  // RGB reflectance of the current material at NBRDF inputs H (3), D (3, folded) and the pair's order (±1).
  function brdfHD(h, d, order) {
    const nets = slotNetworks(state.data), slots = slotWeights(), data = state.data;
    const values = nets.map((net, i) => {
      if (slots.weights[i] === 0) return null;
      const input = [h[0], net.ordered ? order : 0, h[2], ...d];
      return fromMapped(net.mapping, evalNet({...net, row: slots.rows[i]}, input));
    });
    if (nets.length === 1) return values[0];
    const m = data.mapping, y = [0, 0, 0];
    values.forEach((f, i) => {
      if (f) for (let c = 0; c < 3; c++) y[c] += slots.weights[i] * Math.log(m[4] + (f[c] + m[3]) / (m[c] + m[3]));
    });
    return fromMapped(m, y);
  }

  function brdfDirections(wi, wo) {
    const s = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]], length = Math.hypot(...s);
    const h = length > 1e-12 ? s.map((v) => v / length) : [0, 0, 1];
    const rho = Math.hypot(h[0], h[1]);
    const [ct, st, cp, sp] = rho === 0 ? [Math.sign(h[2]), 0, 1, 0] : [h[2], rho, h[0] / rho, h[1] / rho];
    const x = cp * wi[0] + sp * wi[1], y = -sp * wi[0] + cp * wi[1];
    let d = [ct * x - st * wi[2], y, st * x + ct * wi[2]];
    const order = d[1] < -SEAM || (Math.abs(d[1]) <= SEAM && d[0] < -SEAM) ? -1 : 1;
    if (order < 0) d = [-d[0], -d[1], d[2]];
    return brdfHD([rho, 0, h[2]], d, order);
  }

  // ---- the plots ----------------------------------------------------------------------------------------------

  const CHANNELS = ["#e04040", "#30b030", "#4060ff"];

  // BRDF Explorer's in-plane polar plot: ω_o in the plane of incidence, θ_o > 0 on the mirror side; radius on a
  // log scale over DECADES decades below the largest value.
  function polar() {
    const ti = state.thetaI * Math.PI / 180, wi = [Math.sin(ti), 0, Math.cos(ti)];
    const angles = [], rgb = [];
    for (let deg = -89; deg <= 89; deg++) {
      const to = deg * Math.PI / 180;
      angles.push(deg);
      rgb.push(brdfDirections(wi, [-Math.sin(to), 0, Math.cos(to)]));
    }
    view.polar = {theta_i: state.thetaI, theta_o: angles, rgb};
    document.getElementById("polar-values").textContent = JSON.stringify(view.polar);
    const canvas = document.getElementById("polar"), c = canvas.getContext("2d");
    const W = canvas.width, H = canvas.height, cx = W / 2, cy = H - 16, R = Math.min(W / 2, H - 16) - 10;
    const DECADES = 4, top = Math.log10(Math.max(1e-6, ...rgb.flat())), low = top - DECADES;
    const radius = (v) => R * Math.max(0, Math.log10(Math.max(v, 1e-30)) - low) / DECADES;
    c.fillStyle = "#111";
    c.fillRect(0, 0, W, H);
    c.strokeStyle = "#444";
    c.fillStyle = "#888";
    c.font = "10px sans-serif";
    for (let k = 1; k <= DECADES; k++) {  // one ring a decade
      c.beginPath();
      c.arc(cx, cy, R * k / DECADES, Math.PI, 2 * Math.PI);
      c.stroke();
      c.fillText(`${(10 ** (low + k)).toPrecision(1)}`, cx + R * k / DECADES - 14, cy + 12);
    }
    c.beginPath();
    c.moveTo(cx, cy);
    c.lineTo(cx - R * Math.sin(ti), cy - R * Math.cos(ti));  // the incident direction
    c.strokeStyle = "#cc8";
    c.stroke();
    for (let ch = 0; ch < 3; ch++) {
      c.beginPath();
      angles.forEach((deg, i) => {
        const a = deg * Math.PI / 180, r = radius(rgb[i][ch]);
        const px = cx + r * Math.sin(a), py = cy - r * Math.cos(a);
        if (i === 0) c.moveTo(px, py); else c.lineTo(px, py);
      });
      c.strokeStyle = CHANNELS[ch];
      c.stroke();
    }
  }

  // BRDF Explorer's θ_h × θ_d image at one φ_d: θ_h along x, θ_d down y, ln(1 + f) scaled to the image's largest.
  function slice() {
    const canvas = document.getElementById("slice"), c = canvas.getContext("2d"), n = 90;
    const pd = state.phiD * Math.PI / 180, values = new Float64Array(n * n * 3);
    let largest = 1e-12;
    for (let j = 0; j < n; j++) {
      const td = (j + 0.5) * Math.PI / 2 / n;
      const d = [Math.sin(td) * Math.cos(pd), Math.sin(td) * Math.sin(pd), Math.cos(td)];
      for (let i = 0; i < n; i++) {
        const th = (i + 0.5) * Math.PI / 2 / n, f = brdfHD([Math.sin(th), 0, Math.cos(th)], d, 1);
        for (let ch = 0; ch < 3; ch++) {
          const v = Math.log1p(f[ch]);
          values[3 * (j * n + i) + ch] = v;
          largest = Math.max(largest, v);
        }
      }
    }
    const image = c.createImageData(n, n);
    for (let p = 0; p < n * n; p++) {
      for (let ch = 0; ch < 3; ch++) image.data[4 * p + ch] = 255 * Math.pow(values[3 * p + ch] / largest, 1 / 2.2);
      image.data[4 * p + 3] = 255;
    }
    const small = document.createElement("canvas");
    small.width = small.height = n;
    small.getContext("2d").putImageData(image, 0, 0);
    c.imageSmoothingEnabled = false;
    c.drawImage(small, 0, 0, canvas.width, canvas.height);
  }

  // ---- the page -----------------------------------------------------------------------------------------------

  function parameters(data) {
    const q = new URLSearchParams(window.location.search), d = data.defaults;
    const number = (name, fallback, low, high) => {
      if (!q.has(name)) return fallback;
      const v = Number(q.get(name));
      if (!Number.isFinite(v) || v < low || v > high) throw new Error(`URL parameter ${name}=${q.get(name)} must be a number in ${low} … ${high}`);
      return v;
    };
    let light = d.light;
    if (q.has("light")) {
      light = q.get("light").split(",").map(Number);
      if (light.length !== 2 || !light.every(Number.isFinite)) throw new Error(`URL parameter light=${q.get("light")} must be θ,φ in degrees`);
    }
    const flag = (name, fallback) => q.has(name) ? q.get(name) !== "0" : fallback;
    Object.assign(state, {
      data, light, exposure: number("exposure", d.exposure, 1e-6, 1e6), t: number("t", d.t, 0, 1),
      env: flag("env", true), fill: flag("fill", true), key: flag("key", true),
      shape: q.get("shape") === "plane" ? "plane" : "sphere", size: Math.round(number("size", d.size, 16, 2048)),
      thetaI: number("theta_i", d.theta_i, 0, 89), phiD: number("phi_d", d.phi_d, 0, 180),
      chunk: Math.round(number("chunk", d.chunk, 1, 64)), mode: q.get("edit") || (data.edit ? data.edit.modes[0] : null),
    });
    if (data.edit && !data.edit.modes.includes(state.mode)) throw new Error(`URL parameter edit=${state.mode}: this page offers ${data.edit.modes.join(", ")}`);
  }

  function start() {
    let g;
    try {
      const data = readData();
      parameters(data);
      document.title = `${data.title} — frenbrdf view`;
      document.getElementById("title").textContent = data.title;
      document.getElementById("origin").replaceChildren(...data.materials.map((m) => {
        const item = document.createElement("li");
        item.textContent = `${m.name}: ${m.origin}`;
        return item;
      }));
      const canvas = document.getElementById("canvas");
      canvas.width = canvas.height = state.size;
      g = setupGL(canvas, data);
      targets(g, state.size);
    } catch (error) {
      fail(error.message);
      return;
    }
    g.done = 0;
    g.current = 0;
    let pending = true, dirty = true, plotsDirty = true;
    const restart = () => { g.done = 0; pending = dirty = plotsDirty = true; };
    const started = performance.now();

    function frame() {
      try {
        const progressed = pending;
        if (pending) pending = accumulate(g) && g.done < staticLights().length;
        if (dirty || progressed) composite(g);
        dirty = false;
        if (plotsDirty) { polar(); slice(); plotsDirty = false; }
        if (!pending && !view.ready) {
          g.gl.readPixels(0, 0, 1, 1, g.gl.RGBA, g.gl.UNSIGNED_BYTE, new Uint8Array(4));
          view.ready = true;
          view.secondsToConverge = (performance.now() - started) / 1000;
          document.body.dataset.state = "ready";
        }
      } catch (error) {
        fail(error.message);
        return;
      }
      requestAnimationFrame(frame);
    }
    view.redraw = () => { dirty = true; };
    view.restart = restart;
    // Frames per second while the key light turns (the fixed lights cached): what dragging the light costs.
    view.measure = (frames) => {
      const light = state.light.slice(), t0 = performance.now();
      const pixel = new Uint8Array(4);
      for (let i = 0; i < frames; i++) {
        state.light = [light[0], light[1] + 360 * i / frames];
        composite(g);
        g.gl.readPixels(0, 0, 1, 1, g.gl.RGBA, g.gl.UNSIGNED_BYTE, pixel);  // waits for the frame (finish need not)
      }
      state.light = light;
      composite(g);
      return frames / ((performance.now() - t0) / 1000);
    };
    controls(g, restart, () => { dirty = true; }, () => { plotsDirty = true; });
    requestAnimationFrame(frame);
  }

  function controls(g, restart, redraw, replot) {
    const bind = (id, value, apply) => {
      const input = document.getElementById(id);
      input.value = value;
      input.addEventListener("input", () => apply(Number(input.value), input));
      return input;
    };
    bind("exposure", Math.log2(state.exposure), (v) => { state.exposure = 2 ** v; redraw(); });
    bind("theta-i", state.thetaI, (v) => { state.thetaI = v; polar(); });
    bind("phi-d", state.phiD, (v) => { state.phiD = v; slice(); });
    for (const [id, key] of [["env", "env"], ["fill", "fill"]]) {
      const box = document.getElementById(id);
      box.checked = state[key];
      box.addEventListener("change", () => { state[key] = box.checked; restart(); });
    }
    const shape = document.getElementById("shape");
    shape.value = state.shape;
    shape.addEventListener("change", () => { state.shape = shape.value; restart(); });
    const editRow = document.getElementById("edit-row");
    if (state.data.edit) {
      editRow.hidden = false;
      editRow.style.display = "contents";  // its label and slider join the grid
      const last = state.data.edit.keyframes.length - 1;
      const slider = document.getElementById("t");
      slider.max = last;
      bind("t", Math.round(state.t * last), (v) => { state.t = v / last; label(); restart(); });
      const label = () => { document.getElementById("t-value").textContent = `t = ${state.t.toFixed(3)}`; };
      label();
      const mode = document.getElementById("mode");
      mode.replaceChildren(...state.data.edit.modes.map((m) => new Option(
        m === "kept" ? "keeping each material" : "latent interpolation", m)));
      mode.value = state.mode;
      mode.addEventListener("change", () => { state.mode = mode.value; restart(); });
      document.getElementById("ends").textContent = `${state.data.materials[0].name} ↔ ${state.data.materials[1].name}`;
    }
    const canvas = document.getElementById("canvas");
    const drag = (event) => {  // the point under the pointer sets the light: θ = 90° at the sphere's rim, up to 180°
      if (event.type === "pointermove" && !(event.buttons & 1)) return;
      const box = canvas.getBoundingClientRect();
      const x = (event.clientX - box.left) / box.width * 2 - 1, y = 1 - (event.clientY - box.top) / box.height * 2;
      state.light = [Math.min(Math.hypot(x, y), 2) * 90, Math.atan2(y, x) * 180 / Math.PI];
      redraw();
    };
    canvas.addEventListener("pointerdown", drag);
    canvas.addEventListener("pointermove", drag);
    document.getElementById("save").addEventListener("click", () => {
      composite(g);
      canvas.toBlob((blob) => {
        const link = document.createElement("a");
        link.href = URL.createObjectURL(blob);
        link.download = `${state.data.title.replace(/[^\w.-]+/g, "_")}.png`;
        link.click();
        setTimeout(() => URL.revokeObjectURL(link.href), 1000);
      }, "image/png");
    });
  }

  window.addEventListener("error", (event) => fail(String(event.message)));
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start); else start();
})();
