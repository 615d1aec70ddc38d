/* rodcad's 3D view: a small self-contained glTF (glb) viewer, no network, no library.
   Reads the glb embedded in the page (base64) and the side panel's numbers (JSON); draws with
   WebGL (a 2D canvas when WebGL is missing); orbit, pan, zoom, fit; hover and click pick parts
   (an offscreen buffer of part ids) and link them to the tables. */
(function () {
  "use strict";
  var DATA = JSON.parse(document.getElementById("rodcad-data").textContent);
  var canvas = document.getElementById("canvas");
  var view = document.getElementById("view");
  var tip = document.getElementById("tip");
  var side = document.getElementById("side");
  var modeBox = document.getElementById("mode");

  function fail(msg) {
    var d = document.createElement("div");
    d.className = "err";
    d.textContent = "rodcad view: " + msg;
    view.appendChild(d);
    document.body.setAttribute("data-render", "error");
  }

  /* ------------------------------------------------------------------ matrices (column-major) */
  function ident() { return [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]; }
  function mul(a, b) {
    var o = new Array(16);
    for (var c = 0; c < 4; c++) for (var r = 0; r < 4; r++) {
      var s = 0;
      for (var k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      o[c * 4 + r] = s;
    }
    return o;
  }
  function trs(t, q, s) {
    t = t || [0, 0, 0]; q = q || [0, 0, 0, 1]; s = s || [1, 1, 1];
    var x = q[0], y = q[1], z = q[2], w = q[3];
    return [(1 - 2 * (y * y + z * z)) * s[0], 2 * (x * y + z * w) * s[0], 2 * (x * z - y * w) * s[0], 0,
      2 * (x * y - z * w) * s[1], (1 - 2 * (x * x + z * z)) * s[1], 2 * (y * z + x * w) * s[1], 0,
      2 * (x * z + y * w) * s[2], 2 * (y * z - x * w) * s[2], (1 - 2 * (x * x + y * y)) * s[2], 0,
      t[0], t[1], t[2], 1];
  }
  function apply(m, p) {
    return [m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12], m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13],
      m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14]];
  }
  function normalMatrix(m) { /* inverse transpose of the upper 3 x 3 */
    var a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    var A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    var det = a * A + b * B + c * C || 1;
    return [A / det, B / det, C / det, -(b * i - c * h) / det, (a * i - c * g) / det, -(a * h - b * g) / det,
      (b * f - c * e) / det, -(a * f - c * d) / det, (a * e - b * d) / det];
  }
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function norm(a) { var l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }
  function srgb(c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055; }

  /* ------------------------------------------------------------------ the glb */
  function parseGLB(buf) {
    var dv = new DataView(buf);
    if (dv.getUint32(0, true) !== 0x46546C67) throw new Error("not a glb");
    var jlen = dv.getUint32(12, true);
    var json = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 20, jlen)));
    var bin = 20 + jlen + 8;
    function accessor(i) {
      var a = json.accessors[i], bv = json.bufferViews[a.bufferView];
      var n = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 }[a.type];
      var T = { 5126: Float32Array, 5125: Uint32Array, 5123: Uint16Array, 5121: Uint8Array }[a.componentType];
      var off = bin + (bv.byteOffset || 0) + (a.byteOffset || 0), size = T.BYTES_PER_ELEMENT;
      if (bv.byteStride && bv.byteStride !== n * size) {
        var out = new T(a.count * n), src = new DataView(buf);
        for (var k = 0; k < a.count; k++) for (var j = 0; j < n; j++) {
          var o = off + k * bv.byteStride + j * size;
          out[k * n + j] = T === Float32Array ? src.getFloat32(o, true) : T === Uint32Array ? src.getUint32(o, true)
            : T === Uint16Array ? src.getUint16(o, true) : src.getUint8(o);
        }
        return out;
      }
      return new T(buf.slice(off, off + a.count * n * size));
    }
    var meshes = (json.meshes || []).map(function (m) {
      return m.primitives.map(function (p) {
        var mat = p.material != null ? json.materials[p.material] : null;
        var f = (mat && mat.pbrMetallicRoughness && mat.pbrMetallicRoughness.baseColorFactor) || [0.6, 0.6, 0.6, 1];
        var pos = accessor(p.attributes.POSITION);
        var idx = p.indices != null ? accessor(p.indices) : null;
        if (!idx) { idx = new Uint32Array(pos.length / 3); for (var k = 0; k < idx.length; k++) idx[k] = k; }
        var nrm = p.attributes.NORMAL != null ? accessor(p.attributes.NORMAL) : normals(pos, idx);
        return { pos: pos, nrm: nrm, idx: idx, color: [srgb(f[0]), srgb(f[1]), srgb(f[2])] };
      });
    });
    var items = [];
    function walk(i, parent, path) {
      var nd = json.nodes[i];
      var m = mul(parent, nd.matrix || trs(nd.translation, nd.rotation, nd.scale));
      var name = nd.name || ("node " + i);
      if (nd.mesh != null) items.push({ name: name, group: path[path.length - 1] || "", world: m, prims: meshes[nd.mesh] });
      (nd.children || []).forEach(function (c) { walk(c, m, path.concat([name])); });
    }
    var sc = json.scenes[json.scene || 0];
    sc.nodes.forEach(function (i) { walk(i, ident(), []); });
    return { items: items, meshes: meshes, asset: json.asset };
  }
  function normals(pos, idx) {
    var n = new Float32Array(pos.length);
    for (var t = 0; t < idx.length; t += 3) {
      var a = idx[t] * 3, b = idx[t + 1] * 3, c = idx[t + 2] * 3;
      var u = [pos[b] - pos[a], pos[b + 1] - pos[a + 1], pos[b + 2] - pos[a + 2]];
      var v = [pos[c] - pos[a], pos[c + 1] - pos[a + 1], pos[c + 2] - pos[a + 2]];
      var f = cross(u, v);
      for (var k = 0; k < 3; k++) { n[a + k] += f[k]; n[b + k] += f[k]; n[c + k] += f[k]; }
    }
    for (var i = 0; i < n.length; i += 3) {
      var l = Math.hypot(n[i], n[i + 1], n[i + 2]) || 1;
      n[i] /= l; n[i + 1] /= l; n[i + 2] /= l;
    }
    return n;
  }

  var glb;
  try {
    var text = document.getElementById("rodcad-glb").textContent.replace(/\s+/g, "");
    var raw = atob(text), bytes = new Uint8Array(raw.length);
    for (var q = 0; q < raw.length; q++) bytes[q] = raw.charCodeAt(q);
    glb = parseGLB(bytes.buffer);
  } catch (e) { fail("could not read the embedded assembly.glb: " + e.message); return; }
  var items = glb.items;
  items.forEach(function (it, k) {
    it.id = k + 1;
    it.nm = normalMatrix(it.world);
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    it.prims.forEach(function (p) {
      if (!p.box) { /* the mesh's own box, once */
        var a = [Infinity, Infinity, Infinity], b = [-Infinity, -Infinity, -Infinity];
        for (var i = 0; i < p.pos.length; i += 3) for (var j = 0; j < 3; j++) {
          a[j] = Math.min(a[j], p.pos[i + j]); b[j] = Math.max(b[j], p.pos[i + j]);
        }
        p.box = [a, b];
      }
      for (var c = 0; c < 8; c++) {
        var w = apply(it.world, [p.box[c & 1 ? 1 : 0][0], p.box[c & 2 ? 1 : 0][1], p.box[c & 4 ? 1 : 0][2]]);
        for (var j2 = 0; j2 < 3; j2++) { lo[j2] = Math.min(lo[j2], w[j2]); hi[j2] = Math.max(hi[j2], w[j2]); }
      }
    });
    it.box = [lo, hi];
  });
  var byName = {};
  items.forEach(function (it) { byName[it.name] = it; });

  /* ------------------------------------------------------------------ camera */
  var FOV = 30 * Math.PI / 180;
  var cam = { yaw: (DATA.view.yaw || 0) * Math.PI / 180, pitch: (DATA.view.pitch || 0) * Math.PI / 180,
              target: [0, 0, 0], dist: 100, radius: 100 };
  function basis() {
    var cp = Math.cos(cam.pitch), e = [cp * Math.sin(cam.yaw), Math.sin(cam.pitch), cp * Math.cos(cam.yaw)];
    var r = norm(cross([0, 1, 0], e)), u = cross(e, r);
    return { e: e, r: r, u: u };
  }
  function fit(list) {
    list = list && list.length ? list : items;
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    list.forEach(function (it) { for (var j = 0; j < 3; j++) { lo[j] = Math.min(lo[j], it.box[0][j]); hi[j] = Math.max(hi[j], it.box[1][j]); } });
    if (!isFinite(lo[0])) { lo = [-50, -50, -50]; hi = [50, 50, 50]; }
    var c = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
    cam.target = c;
    cam.radius = Math.max(Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2, 1);
    var b = basis(), aspect = canvas.width / Math.max(canvas.height, 1);
    var ty = Math.tan(FOV / 2), tx = ty * aspect, d = 0;
    for (var k = 0; k < 8; k++) {
      var p = sub([k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]], c);
      var x = dot(p, b.r), y = dot(p, b.u), z = dot(p, b.e);
      d = Math.max(d, z + Math.abs(x) / tx, z + Math.abs(y) / ty);
    }
    cam.dist = d * 1.12;
    if (list === items) cam.all = cam.radius;
    redraw();
  }
  function matrices() {
    var b = basis(), eye = [cam.target[0] + cam.dist * b.e[0], cam.target[1] + cam.dist * b.e[1], cam.target[2] + cam.dist * b.e[2]];
    var f = [-b.e[0], -b.e[1], -b.e[2]];
    var viewM = [b.r[0], b.u[0], -f[0], 0, b.r[1], b.u[1], -f[1], 0, b.r[2], b.u[2], -f[2], 0,
      -dot(b.r, eye), -dot(b.u, eye), dot(f, eye), 1];
    var R = cam.all || cam.radius, near = Math.max(cam.dist - 3 * R, cam.dist / 200, 0.01), far = cam.dist + 3 * R;
    var aspect = canvas.width / Math.max(canvas.height, 1), t = 1 / Math.tan(FOV / 2);
    var proj = [t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0];
    var key = norm([0.75 * b.e[0] + 0.55 * b.u[0] - 0.4 * b.r[0], 0.75 * b.e[1] + 0.55 * b.u[1] - 0.4 * b.r[1],
      0.75 * b.e[2] + 0.55 * b.u[2] - 0.4 * b.r[2]]);
    return { vp: mul(proj, viewM), eye: eye, key: key, b: b };
  }

  /* ------------------------------------------------------------------ WebGL */
  var gl = null, renderer = null;
  try { gl = canvas.getContext("webgl2", { antialias: true }) || canvas.getContext("webgl", { antialias: true }); } catch (e) { gl = null; }
  if (gl && !(typeof WebGL2RenderingContext !== "undefined" && gl instanceof WebGL2RenderingContext)
      && !gl.getExtension("OES_element_index_uint")) gl = null;

  function webgl() {
    var VS = "attribute vec3 aP; attribute vec3 aN; uniform mat4 uVP; uniform mat4 uM; uniform mat3 uNM;" +
      "varying vec3 vN; varying vec3 vW; void main() { vec4 w = uM * vec4(aP, 1.0); vW = w.xyz; vN = uNM * aN; gl_Position = uVP * w; }";
    var FS = "precision highp float; varying vec3 vN; varying vec3 vW; uniform vec3 uC; uniform vec3 uEye; uniform vec3 uKey; uniform float uHi;" +
      "void main() { vec3 n = normalize(vN); vec3 v = normalize(uEye - vW); if (dot(n, v) < 0.0) n = -n;" +
      " float d = max(dot(n, uKey), 0.0); float hemi = 0.5 + 0.5 * n.y; vec3 h = normalize(uKey + v);" +
      " float s = pow(max(dot(n, h), 0.0), 48.0);" +
      " vec3 c = uC * (0.30 + 0.20 * hemi + 0.60 * d) + vec3(0.16 * s);" +
      " c = mix(c, vec3(1.0, 0.86, 0.15), 0.6 * uHi); gl_FragColor = vec4(c, 1.0); }";
    var PFS = "precision highp float; varying vec3 vN; varying vec3 vW; uniform vec3 uC; void main() { gl_FragColor = vec4(uC, 1.0); }";
    function program(vs, fs) {
      var p = gl.createProgram();
      [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]].forEach(function (x) {
        var s = gl.createShader(x[0]);
        gl.shaderSource(s, x[1]); gl.compileShader(s);
        if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
        gl.attachShader(p, s);
      });
      gl.bindAttribLocation(p, 0, "aP"); gl.bindAttribLocation(p, 1, "aN");
      gl.linkProgram(p);
      if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
      var u = {};
      ["uVP", "uM", "uNM", "uC", "uEye", "uKey", "uHi"].forEach(function (n) { u[n] = gl.getUniformLocation(p, n); });
      return { p: p, u: u };
    }
    var shade = program(VS, FS), pick = program(VS, PFS);
    glb.meshes.forEach(function (prims) {
      prims.forEach(function (p) {
        p.vb = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, p.vb); gl.bufferData(gl.ARRAY_BUFFER, p.pos, gl.STATIC_DRAW);
        p.nb = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, p.nb); gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(p.nrm), gl.STATIC_DRAW);
        p.ib = gl.createBuffer(); gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, p.ib);
        var idx = p.idx instanceof Uint32Array ? p.idx : new Uint32Array(p.idx);
        gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.STATIC_DRAW);
        p.count = idx.length;
      });
    });
    gl.enable(gl.DEPTH_TEST);
    gl.enableVertexAttribArray(0); gl.enableVertexAttribArray(1);
    var fbo = null, fw = 0, fh = 0, tex = null, depth = null;
    function drawAll(prog, m, picking) {
      gl.useProgram(prog.p);
      gl.uniformMatrix4fv(prog.u.uVP, false, new Float32Array(m.vp));
      if (!picking) { gl.uniform3fv(prog.u.uEye, m.eye); gl.uniform3fv(prog.u.uKey, m.key); }
      items.forEach(function (it) {
        if (it.hidden) return;
        gl.uniformMatrix4fv(prog.u.uM, false, new Float32Array(it.world));
        gl.uniformMatrix3fv(prog.u.uNM, false, new Float32Array(it.nm));
        if (picking) gl.uniform3f(prog.u.uC, (it.id & 255) / 255, ((it.id >> 8) & 255) / 255, ((it.id >> 16) & 255) / 255);
        else gl.uniform1f(prog.u.uHi, lit(it) ? 1 : 0);
        it.prims.forEach(function (p) {
          if (!picking) gl.uniform3fv(prog.u.uC, p.color);
          gl.bindBuffer(gl.ARRAY_BUFFER, p.vb); gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
          gl.bindBuffer(gl.ARRAY_BUFFER, p.nb); gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 0, 0);
          gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, p.ib);
          gl.drawElements(gl.TRIANGLES, p.count, gl.UNSIGNED_INT, 0);
        });
      });
    }
    return {
      name: "WebGL " + (gl instanceof (window.WebGL2RenderingContext || function () {}) ? "2" : "1"),
      draw: function () {
        var m = matrices();
        gl.bindFramebuffer(gl.FRAMEBUFFER, null);
        gl.viewport(0, 0, canvas.width, canvas.height);
        gl.clearColor(0, 0, 0, 0); gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        drawAll(shade, m, false);
      },
      pick: function (x, y) {
        if (!fbo || fw !== canvas.width || fh !== canvas.height) {
          fw = canvas.width; fh = canvas.height;
          fbo = fbo || gl.createFramebuffer(); tex = tex || gl.createTexture(); depth = depth || gl.createRenderbuffer();
          gl.bindTexture(gl.TEXTURE_2D, tex);
          gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, fw, fh, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
          gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
          gl.bindRenderbuffer(gl.RENDERBUFFER, depth);
          gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT16, fw, fh);
          gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
          gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
          gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
        }
        gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
        gl.viewport(0, 0, fw, fh);
        gl.disable(gl.BLEND);
        gl.clearColor(0, 0, 0, 0); gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        drawAll(pick, matrices(), true);
        var px = new Uint8Array(4);
        gl.readPixels(Math.round(x), Math.round(fh - 1 - y), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
        gl.bindFramebuffer(gl.FRAMEBUFFER, null);
        var id = px[0] | (px[1] << 8) | (px[2] << 16);
        return id ? items[id - 1] : null;
      }
    };
  }

  /* ------------------------------------------------------------------ 2D canvas fallback */
  function canvas2d() {
    var ctx = canvas.getContext("2d"), tris = [];
    items.forEach(function (it) {
      it.prims.forEach(function (p) {
        var w = [];
        for (var i = 0; i < p.pos.length; i += 3) w.push(apply(it.world, [p.pos[i], p.pos[i + 1], p.pos[i + 2]]));
        for (var t = 0; t < p.idx.length; t += 3) {
          var a = w[p.idx[t]], b = w[p.idx[t + 1]], c = w[p.idx[t + 2]];
          tris.push({ a: a, b: b, c: c, n: norm(cross(sub(b, a), sub(c, a))), color: p.color, it: it });
        }
      });
    });
    var drawn = [];
    return {
      name: "2D canvas (no WebGL)",
      draw: function () {
        var m = matrices(), W = canvas.width, H = canvas.height;
        ctx.clearRect(0, 0, W, H);
        function proj(p) {
          var v = m.vp, x = v[0] * p[0] + v[4] * p[1] + v[8] * p[2] + v[12], y = v[1] * p[0] + v[5] * p[1] + v[9] * p[2] + v[13],
            ww = v[3] * p[0] + v[7] * p[1] + v[11] * p[2] + v[15];
          return [(x / ww + 1) * W / 2, (1 - y / ww) * H / 2, ww];
        }
        drawn = [];
        tris.forEach(function (t) {
          if (t.it.hidden) return;
          var a = proj(t.a), b = proj(t.b), c = proj(t.c);
          if (a[2] <= 0 || b[2] <= 0 || c[2] <= 0) return;
          drawn.push({ a: a, b: b, c: c, z: a[2] + b[2] + c[2], t: t });
        });
        drawn.sort(function (p, q) { return q.z - p.z; });
        drawn.forEach(function (d) {
          var n = d.t.n, v = norm(sub(m.eye, d.t.a));
          if (dot(n, v) < 0) n = [-n[0], -n[1], -n[2]];
          var k = 0.30 + 0.20 * (0.5 + 0.5 * n[1]) + 0.60 * Math.max(dot(n, m.key), 0), hi = lit(d.t.it) ? 0.6 : 0;
          var col = d.t.color.map(function (c, j) { return Math.round(255 * Math.min(1, (c * k) * (1 - hi) + hi * [1, 0.86, 0.15][j])); });
          ctx.fillStyle = ctx.strokeStyle = "rgb(" + col.join(",") + ")";
          ctx.beginPath(); ctx.moveTo(d.a[0], d.a[1]); ctx.lineTo(d.b[0], d.b[1]); ctx.lineTo(d.c[0], d.c[1]); ctx.closePath();
          ctx.fill(); ctx.stroke();
        });
      },
      pick: function (x, y) {
        for (var i = drawn.length - 1; i >= 0; i--) {
          var d = drawn[i], s1 = side(d.a, d.b, x, y), s2 = side(d.b, d.c, x, y), s3 = side(d.c, d.a, x, y);
          if ((s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0)) return d.t.it;
        }
        return null;
      }
    };
    function side(p, q, x, y) { return (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0]); }
  }

  /* ------------------------------------------------------------------ selection and the panel */
  var hover = null, hoverRow = null, selected = [], rowsOf = {};
  function lit(it) { return it === hover || (hoverRow && hoverRow.indexOf(it) >= 0) || selected.indexOf(it) >= 0; }
  function fmt(v, digits) {
    if (v === null || v === undefined) return "-";
    if (typeof v !== "number") return String(v);
    if (digits === undefined) return Number.isInteger(v) ? String(v) : v.toPrecision(4);
    var a = Math.abs(v);
    if (a !== 0 && (a >= 1e6 || a < Math.pow(10, -digits))) return v.toPrecision(3);
    return v.toFixed(digits);
  }
  function el(tag, cls, text) { var e = document.createElement(tag); if (cls) e.className = cls; if (text != null) e.textContent = text; return e; }
  var panel = DATA.panel || {}, selBox;
  function buildPanel() {
    side.appendChild(el("h1", null, panel.title || ""));
    if (panel.subtitle) side.appendChild(el("div", "sub", panel.subtitle));
    var dl = el("dl");
    (panel.summary || []).forEach(function (r) { dl.appendChild(el("dt", null, r[0])); dl.appendChild(el("dd", null, r[1])); });
    side.appendChild(dl);
    var lg = panel.legend;
    if (lg) {
      var box = el("div", "legend");
      box.appendChild(el("div", null, lg.label));
      var bar = el("div", "bar");
      bar.style.background = "linear-gradient(to right," + lg.stops.join(",") + ")";
      box.appendChild(bar);
      var ends = el("div", "ends");
      ends.appendChild(el("span", null, fmt(lg.lo, 2) + " g (light)"));
      ends.appendChild(el("span", null, fmt(lg.hi, 2) + " g (heavy)"));
      box.appendChild(ends);
      var keys = el("div", "keys");
      (lg.keys || []).forEach(function (k) {
        var s = el("span"), sw = el("span", "sw");
        sw.style.background = k.color; s.appendChild(sw); s.appendChild(document.createTextNode(k.label)); keys.appendChild(s);
      });
      box.appendChild(keys);
      side.appendChild(box);
    }
    selBox = el("div"); selBox.id = "sel"; selBox.textContent = "Hover or click a part, or a row of a table.";
    side.appendChild(selBox);
    (panel.tables || []).forEach(function (t) { side.appendChild(table(t)); });
  }
  function table(t) {
    var det = el("details"); det.open = true;
    det.appendChild(el("summary", null, t.title + " (" + t.rows.length + ")"));
    var wrap = el("div", "tablewrap"), tab = el("table", "data"), head = el("tr"), body = el("tbody");
    t.columns.forEach(function (c, j) {
      var th = el("th", null, c.label);
      th.title = "sort by " + c.label;
      th.onclick = function () { sortBy(j); };
      head.appendChild(th);
    });
    var thead = el("thead"); thead.appendChild(head); tab.appendChild(thead); tab.appendChild(body);
    var trs = t.rows.map(function (row, i) {
      var tr = el("tr");
      row.forEach(function (v, j) { tr.appendChild(el("td", typeof v === "number" ? "num" : null, fmt(v, t.columns[j].digits))); });
      var parts = (t.parts && t.parts[i] || []).map(function (n) { return byName[n]; }).filter(Boolean);
      tr._parts = parts; tr._row = row; tr._table = t;
      parts.forEach(function (it) { (rowsOf[it.name] = rowsOf[it.name] || []).push(tr); });
      tr.onmouseenter = function () { hoverRow = parts; redraw(); };
      tr.onmouseleave = function () { hoverRow = null; redraw(); };
      tr.onclick = function () { select(parts, tr); };
      tr.ondblclick = function () { if (parts.length) fit(parts); };
      body.appendChild(tr);
      return tr;
    });
    var order = 1, last = -1;
    function sortBy(j) {
      order = last === j ? -order : 1; last = j;
      trs.slice().sort(function (a, b) {
        var x = a._row[j], y = b._row[j];
        if (x === y) return 0;
        if (x === null || x === undefined) return 1;
        if (y === null || y === undefined) return -1;
        return (typeof x === "number" && typeof y === "number" ? x - y : String(x).localeCompare(String(y), undefined, { numeric: true })) * order;
      }).forEach(function (tr) { body.appendChild(tr); });
    }
    wrap.appendChild(tab); det.appendChild(wrap);
    return det;
  }
  function describe(it) {
    var box = el("div"), rows = rowsOf[it.name] || [];
    box.appendChild(el("b", null, it.name));
    rows.forEach(function (tr) {
      var tab = el("table");
      tr._table.columns.forEach(function (c, j) {
        var r = el("tr"); r.appendChild(el("td", null, c.label)); r.appendChild(el("td", null, fmt(tr._row[j], c.digits))); tab.appendChild(r);
      });
      box.appendChild(el("div", null, tr._table.title)); box.appendChild(tab);
    });
    if (!rows.length) box.appendChild(el("div", null, it.group));
    return box;
  }
  function select(parts, tr) {
    selected = parts || [];
    document.querySelectorAll("tr.on").forEach(function (r) { r.classList.remove("on"); });
    var rows = tr ? [tr] : [];
    selected.forEach(function (it) { rows = rows.concat(rowsOf[it.name] || []); });
    rows.forEach(function (r) { r.classList.add("on"); });
    if (rows.length && !tr) rows[0].scrollIntoView({ block: "nearest" });
    selBox.textContent = "";
    if (!selected.length) selBox.textContent = "Hover or click a part, or a row of a table.";
    else if (selected.length === 1) selBox.appendChild(describe(selected[0]));
    else selBox.appendChild(el("b", null, selected.length + " parts: " + selected.map(function (it) { return it.name; }).slice(0, 8).join(", ") + (selected.length > 8 ? ", ..." : "")));
    redraw();
  }

  /* ------------------------------------------------------------------ drawing and input */
  var pending = false;
  function redraw() { if (!pending && renderer) { pending = true; requestAnimationFrame(function () { pending = false; renderer.draw(); }); } }
  function resize() {
    var r = window.devicePixelRatio || 1, w = Math.max(1, Math.round(view.clientWidth * r)), h = Math.max(1, Math.round(view.clientHeight * r));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; return true; }
    return false;
  }
  var drag = null;
  function bind() {
    canvas.addEventListener("contextmenu", function (e) { e.preventDefault(); });
    canvas.addEventListener("pointerdown", function (e) {
      drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.button === 1 || e.shiftKey, moved: 0 };
      canvas.setPointerCapture(e.pointerId); canvas.classList.add("dragging");
    });
    canvas.addEventListener("pointermove", function (e) {
      if (drag) {
        var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
        drag.x = e.clientX; drag.y = e.clientY; drag.moved += Math.abs(dx) + Math.abs(dy);
      cam.moved = true;
        if (drag.pan) {
          var b = basis(), s = 2 * cam.dist * Math.tan(FOV / 2) / Math.max(view.clientHeight, 1);
          for (var j = 0; j < 3; j++) cam.target[j] += (-dx * b.r[j] + dy * b.u[j]) * s;
        } else {
          cam.yaw -= dx * 0.008;
          cam.pitch = Math.max(-1.55, Math.min(1.55, cam.pitch + dy * 0.008));
        }
        tip.style.display = "none";
        redraw();
        return;
      }
      hoverAt(e);
    });
    canvas.addEventListener("pointerup", function (e) {
      canvas.classList.remove("dragging");
      if (drag && drag.moved < 4) { var it = pickAt(e); select(it ? [it] : []); }
      drag = null;
    });
    canvas.addEventListener("pointerleave", function () { if (!drag) { hover = null; tip.style.display = "none"; redraw(); } });
    canvas.addEventListener("wheel", function (e) {
      e.preventDefault();
      cam.moved = true;
    cam.dist *= Math.exp(Math.max(-1, Math.min(1, e.deltaY * (e.deltaMode ? 0.05 : 0.0015))));
      redraw();
    }, { passive: false });
    canvas.addEventListener("dblclick", function () { fit(); });
  }
  window.addEventListener("keydown", function (e) {
    if (e.key === "f" || e.key === "F") fit(selected.length ? selected : null);
    if (e.key === "Escape") select([]);
  });
  function onResize() { if (resize()) { if (cam.moved) redraw(); else fit(); } } /* framed again until moved */
  window.addEventListener("resize", onResize);
  if (window.ResizeObserver) new ResizeObserver(onResize).observe(view);
  function pickAt(e) {
    var r = canvas.getBoundingClientRect(), s = canvas.width / Math.max(r.width, 1);
    return renderer.pick((e.clientX - r.left) * s, (e.clientY - r.top) * s);
  }
  function hoverAt(e) {
    var it = pickAt(e);
    if (it !== hover) { hover = it; redraw(); }
    if (!it) { tip.style.display = "none"; return; }
    var r = view.getBoundingClientRect();
    tip.textContent = ""; tip.appendChild(describe(it));
    tip.style.display = "block";
    var x = e.clientX - r.left + 14, y = e.clientY - r.top + 14;
    if (x + tip.offsetWidth > r.width) x = Math.max(0, e.clientX - r.left - tip.offsetWidth - 10);
    if (y + tip.offsetHeight > r.height) y = Math.max(0, e.clientY - r.top - tip.offsetHeight - 10);
    tip.style.left = x + "px"; tip.style.top = y + "px";
  }

  buildPanel();
  resize();
  try { renderer = gl ? webgl() : null; } catch (e) { renderer = null; }
  if (!renderer) {
    if (gl) { /* a canvas keeps the first kind of context it gave: draw on a fresh one */
      var fresh = canvas.cloneNode(false);
      canvas.parentNode.replaceChild(fresh, canvas);
      canvas = fresh;
      resize();
    }
    renderer = canvas2d();
  }
  bind();
  modeBox.textContent = renderer.name + " \u00b7 " + items.length + " parts";
  document.body.setAttribute("data-render", renderer.name.split(" ")[0] === "WebGL" ? "webgl" : "canvas2d");
  fit();
  renderer.draw();
  /* for scripts and tests: the parts, what is at a point of the canvas, select by name */
  window.rodcadView = {
    renderer: renderer.name, parts: items.map(function (it) { return it.name; }),
    pick: function (x, y) { var it = renderer.pick(x, y); return it ? it.name : null; },
    select: function (names) { select(names.map(function (n) { return byName[n]; }).filter(Boolean)); },
    selected: function () { return selected.map(function (it) { return it.name; }); }
  };
})();
