// lambert's viewer page (docs/viewer.md): the .glb embedded in the page (base64, so that the
// page works from file:// with no network), drawn with three.js (viewer/three.bundle.js).
//
// The glb holds per-vertex radiosity B (W/m²): COLOR_0 the solution, COLOR_k the solution for
// emitter k alone (asset.extras.lambert.emitters). By linearity the picture for intensities
// w_k (times a colour) is Σ_k w_k B_k, summed per vertex in the vertex shader, so a slider
// move costs one redraw. The picture is tone-mapped like lambert's PNG: radiance B/π times
// 2^EV, clipped, sRGB-encoded. False colour maps the luminance of that sum (or, for heat
// results, _TEMPERATURE or _HEAT_FLUX) through viridis, with a colour bar.
//
// The page's state lives in the URL's fragment (#ev=-1.5&w1=0.5&c1=ffcc88&mode=radiosity&
// edges=1&ui=0), read on load and written on every change: a view can be shared or scripted
// (the browser test sets it). ui=0 hides the panels.
(function () {
  'use strict';
  const T = window.LAMBERT_THREE;
  const $ = (id) => document.getElementById(id);
  const VIRIDIS = [[68, 1, 84], [71, 44, 122], [59, 81, 139], [44, 113, 142], [33, 144, 140],
    [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37]];
  const LUMINANCE = [0.2126, 0.7152, 0.0722];  // Rec. 709, as io/tonemap

  function fail(message) {
    $('error').textContent = message;
    $('error').style.display = 'block';
    document.body.dataset.state = 'error';
  }

  function decode(base64) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
    return bytes.buffer;
  }

  const hash = new URLSearchParams(location.hash.slice(1));
  const number = (key, fallback) => {
    const v = parseFloat(hash.get(key));
    return Number.isFinite(v) ? v : fallback;
  };
  if (hash.get('ui') === '0') document.body.classList.add('bare');

  let renderer;
  try {
    renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    fail('This page needs WebGL, which this browser does not offer: ' + e.message);
    return;
  }
  renderer.outputColorSpace = T.LinearSRGBColorSpace;  // the shaders write sRGB themselves
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  $('view').appendChild(renderer.domElement);

  new T.GLTFLoader().parse(decode(window.LAMBERT_GLB_BASE64), '', start,
    (e) => fail('The embedded .glb cannot be read: ' + (e && e.message ? e.message : e)));

  function rampTexture() {
    const n = 256, data = new Uint8Array(4 * n);
    for (let i = 0; i < n; ++i) {
      const x = i / (n - 1) * (VIRIDIS.length - 1), k = Math.min(Math.floor(x), VIRIDIS.length - 2);
      const f = x - k;
      for (let c = 0; c < 3; ++c)
        data[4 * i + c] = Math.round(VIRIDIS[k][c] * (1 - f) + VIRIDIS[k + 1][c] * f);
      data[4 * i + 3] = 255;
    }
    const t = new T.DataTexture(data, n, 1, T.RGBAFormat, T.UnsignedByteType);
    t.magFilter = t.minFilter = T.LinearFilter;
    t.wrapS = t.wrapT = T.ClampToEdgeWrapping;
    t.needsUpdate = true;
    return { texture: t, data };
  }

  function start(gltf) {
    const info = ((gltf.parser.json.asset || {}).extras || {}).lambert || {};
    const emitters = info.emitters || [];
    let mesh = null, edges = null;
    gltf.scene.traverse((o) => {
      if (o.isMesh && !mesh) mesh = o;
      if (o.isLineSegments) edges = o;
    });
    if (!mesh) return fail('The .glb holds no triangle mesh.');
    const geometry = mesh.geometry;
    const attribute = (name) => geometry.getAttribute(name);
    const bases = emitters.map((e) => e.attribute.toLowerCase()).filter((a) => attribute(a));
    const scalars = { temperature: '_temperature', flux: '_heat_flux' };

    // What can be shown: the picture and false colour of radiosity, temperature and flux.
    const modes = [];
    if (attribute('color')) modes.push(['picture', 'picture'], ['radiosity', 'radiosity (false colour)']);
    if (attribute('_temperature')) modes.push(['temperature', 'temperature (false colour)']);
    if (attribute('_heat_flux')) modes.push(['flux', 'net heat flux (false colour)']);
    if (!modes.length) return fail('The .glb has no radiosity, temperature or flux per vertex.');
    for (const [value, text] of modes) $('mode').add(new Option(text, value));
    const wanted = hash.get('mode') || info.default_mode;  // heat results: the temperature
    $('mode').value = modes.some(([v]) => v === wanted) ? wanted : modes[0][0];

    const ramp = rampTexture();
    const uniforms = {
      exposure: { value: 1 }, mode: { value: 0 }, lo: { value: 0 }, hi: { value: 1 },
      ramp: { value: ramp.texture },
      weights: { value: bases.map(() => new T.Vector3(1, 1, 1)) },
    };
    const declare = bases.map((a) => `attribute vec3 ${a};`).join('\n');
    const mix = bases.length
      ? bases.map((a, k) => `weights[${k}] * ${a}`).join(' + ')
      : (attribute('color') ? 'color' : 'vec3(0.0)');
    const scalar = (name) => (attribute(name) ? `attribute float ${name};` : '');
    const material = new T.ShaderMaterial({
      uniforms,
      side: T.DoubleSide,
      vertexShader: `
        ${attribute('color') ? 'attribute vec3 color;' : ''}
        ${declare}
        ${scalar('_temperature')}
        ${scalar('_heat_flux')}
        ${bases.length ? `uniform vec3 weights[${bases.length}];` : ''}
        uniform int mode;
        varying vec3 vRadiosity;
        varying float vScalar;
        void main() {
          vRadiosity = ${mix};
          vScalar = dot(vRadiosity, vec3(${LUMINANCE.join(', ')}));
          ${attribute('_temperature') ? 'if (mode == 2) vScalar = _temperature;' : ''}
          ${attribute('_heat_flux') ? 'if (mode == 3) vScalar = _heat_flux;' : ''}
          gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
        }`,
      fragmentShader: `
        uniform float exposure, lo, hi;
        uniform int mode;
        uniform sampler2D ramp;
        varying vec3 vRadiosity;
        varying float vScalar;
        float srgb(float x) {
          x = clamp(x, 0.0, 1.0);
          return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
        }
        void main() {
          if (mode == 0) {
            vec3 L = vRadiosity * (exposure / 3.141592653589793);
            gl_FragColor = vec4(srgb(L.r), srgb(L.g), srgb(L.b), 1.0);
          } else {
            float t = clamp((vScalar - lo) / max(hi - lo, 1e-30), 0.0, 1.0);
            gl_FragColor = vec4(texture2D(ramp, vec2(t * 255.0 / 256.0 + 0.5 / 256.0, 0.5)).rgb, 1.0);
          }
        }`,
    });
    mesh.material = material;
    if (edges) {
      edges.material = new T.LineBasicMaterial({ color: 0x000000 });
      edges.visible = false;
    }

    // The camera of the run (node extras: its target), else one framing the scene.
    const scene = new T.Scene();
    scene.add(gltf.scene);
    const json = gltf.parser.json;
    const node = (json.nodes || []).find((n) => n.camera !== undefined);
    geometry.computeBoundingSphere();
    const sphere = geometry.boundingSphere;
    const cameraInfo = node ? json.cameras[node.camera].perspective : { yfov: 0.7 };
    const camera = new T.PerspectiveCamera(cameraInfo.yfov * 180 / Math.PI, 1,
      sphere.radius * 1e-3, sphere.radius * 100);
    const target = new T.Vector3();
    if (node) {
      const q = node.rotation || [0, 0, 0, 1];
      camera.position.fromArray(node.translation || [0, 0, 0]);
      camera.quaternion.set(q[0], q[1], q[2], q[3]);
      camera.up.set(0, 1, 0).applyQuaternion(camera.quaternion);
      if (node.extras && node.extras.target) target.fromArray(node.extras.target);
      else target.set(0, 0, -1).applyQuaternion(camera.quaternion).add(camera.position);
    } else {
      target.copy(sphere.center);
      camera.position.copy(sphere.center).add(new T.Vector3(0, 0, 3 * sphere.radius));
    }
    const controls = new T.OrbitControls(camera, renderer.domElement);
    controls.target.copy(target);
    controls.update();

    // The panel.
    $('title').textContent = (info.scene || 'lambert').split('/').pop();
    const vertices = attribute('position').count;
    $('facts').textContent = `${vertices} vertices · ${emitters.length} light source` +
      `${emitters.length === 1 ? '' : 's'}` +
      (info.linearity_error !== undefined ? ` · bases sum to the solution within ${info.linearity_error.toExponential(1)}` : '') +
      (info.no_relighting ? ` · ${info.no_relighting}` : '');
    const ev0 = info.exposure_ev || 0;
    $('ev').min = ev0 - 10;
    $('ev').max = ev0 + 10;
    $('ev').value = number('ev', ev0);
    const lights = emitters.map((e, k) => {
      const row = document.createElement('div');
      row.className = 'row';
      const id = `w${k + 1}`;
      row.innerHTML = `<label for="${id}"></label><input id="${id}" type="range" min="0" max="4" step="0.01">` +
        `<span class="value"></span><input type="color" value="#ffffff" title="colour">`;
      row.querySelector('label').textContent = e.name;
      row.querySelector('label').title = (e.surfaces || []).join(', ') || e.name;
      const [slider, value, colour] = [row.querySelector('input[type=range]'), row.querySelector('.value'),
        row.querySelector('input[type=color]')];
      slider.value = number(id, 1);
      const c = hash.get(`c${k + 1}`);
      if (c && /^[0-9a-fA-F]{6}$/.test(c)) colour.value = '#' + c.toLowerCase();
      $('lights').appendChild(row);
      return { slider, value, colour };
    });
    $('edges').checked = hash.get('edges') === '1';
    $('edges').disabled = !edges;

    const linear = (byte) => {
      const x = byte / 255;
      return x <= 0.04045 ? x / 12.92 : Math.pow((x + 0.055) / 1.055, 2.4);
    };
    function currentWeights() {
      return lights.map(({ slider, colour }) => {
        const w = parseFloat(slider.value), hex = colour.value.slice(1);
        return [0, 2, 4].map((i) => w * linear(parseInt(hex.substr(i, 2), 16)));
      });
    }
    // The false-colour range of the current mix: 0 to the 99th percentile of the luminance
    // (an emitter's own radiosity would otherwise squash the rest); min to max of T or q.
    function range(mode, weights) {
      const n = vertices;
      const values = new Float64Array(n);
      if (mode === 'radiosity') {
        const arrays = bases.length ? bases.map((a) => attribute(a).array) : [attribute('color').array];
        const w = bases.length ? weights : [[1, 1, 1]];
        for (let i = 0; i < n; ++i) {
          let v = 0;
          for (let k = 0; k < arrays.length; ++k)
            for (let c = 0; c < 3; ++c) v += LUMINANCE[c] * w[k][c] * arrays[k][3 * i + c];
          values[i] = v;
        }
        values.sort();
        return [0, values[Math.min(n - 1, Math.floor(0.99 * n))]];
      }
      const array = attribute(scalars[mode]).array;
      let lo = Infinity, hi = -Infinity;
      for (let i = 0; i < n; ++i) { lo = Math.min(lo, array[i]); hi = Math.max(hi, array[i]); }
      return [lo, hi];
    }
    const units = { radiosity: 'W/m²', temperature: 'K', flux: 'W/m²' };
    function drawBar(mode, lo, hi) {
      $('bar').style.display = mode === 'picture' ? 'none' : 'block';
      if (mode === 'picture') return;
      const canvas = $('bar-canvas'), ctx = canvas.getContext('2d'), image = ctx.createImageData(256, 1);
      image.data.set(ramp.data);
      ctx.putImageData(image, 0, 0);
      const fmt = (x) => (Math.abs(x) >= 1e4 || (Math.abs(x) < 1e-2 && x !== 0) ? x.toExponential(2) : x.toPrecision(3));
      $('bar-lo').textContent = fmt(lo);
      $('bar-hi').textContent = fmt(hi);
      $('bar-unit').textContent = units[mode];
    }

    // The sky behind the scene (asset.extras.lambert.sky_radiance), as lambert's renderer draws
    // it on rays that miss: its radiance times the sky slider, exposed and sRGB-encoded.
    const skyIndex = emitters.findIndex((e) => e.kind === 'sky');
    const srgb = (x) => {
      x = Math.min(Math.max(x, 0), 1);
      return x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055;
    };
    function background(mode, weights, exposure) {
      const sky = info.sky_radiance;
      if (!sky || mode !== 'picture') return renderer.setClearColor(0x000000);
      const w = skyIndex >= 0 ? weights[skyIndex] : [1, 1, 1];
      renderer.setClearColor(new T.Color(...[0, 1, 2].map((c) => srgb(sky[c] * w[c] * exposure))));
    }

    function draw() {
      renderer.render(scene, camera);
    }
    function update() {
      const mode = $('mode').value;
      const ev = parseFloat($('ev').value);
      $('ev-value').textContent = (ev >= 0 ? '+' : '') + ev.toFixed(2);
      const weights = currentWeights();
      weights.forEach((w, k) => {
        uniforms.weights.value[k].set(w[0], w[1], w[2]);
        lights[k].value.textContent = parseFloat(lights[k].slider.value).toFixed(2);
      });
      uniforms.exposure.value = Math.pow(2, ev);
      background(mode, weights, uniforms.exposure.value);
      uniforms.mode.value = { picture: 0, radiosity: 1, temperature: 2, flux: 3 }[mode];
      if (mode !== 'picture') {
        const [lo, hi] = range(mode, weights);
        uniforms.lo.value = lo;
        uniforms.hi.value = hi;
        drawBar(mode, lo, hi);
      } else {
        drawBar(mode);
      }
      if (edges) edges.visible = $('edges').checked;
      const state = new URLSearchParams();
      state.set('ev', ev.toFixed(2));
      lights.forEach(({ slider, colour }, k) => {
        if (parseFloat(slider.value) !== 1) state.set(`w${k + 1}`, slider.value);
        if (colour.value !== '#ffffff') state.set(`c${k + 1}`, colour.value.slice(1));
      });
      if (mode !== modes[0][0]) state.set('mode', mode);
      if ($('edges').checked) state.set('edges', '1');
      if (hash.get('ui') === '0') state.set('ui', '0');
      history.replaceState(null, '', '#' + state.toString());
      draw();
    }
    function resize() {
      const w = window.innerWidth, h = window.innerHeight;
      renderer.setSize(w, h);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      draw();
    }

    // Walking: W/S forward and back, A/D sideways, Q/E down and up, camera and target together.
    const held = new Set();
    let last = 0;
    function walk(time) {
      if (!held.size) { last = 0; return; }
      const dt = last ? Math.min(0.1, (time - last) / 1000) : 0;
      last = time;
      const forward = new T.Vector3().subVectors(controls.target, camera.position).normalize();
      const side = new T.Vector3().crossVectors(forward, camera.up).normalize();
      const step = new T.Vector3();
      const speed = 0.5 * sphere.radius * dt;
      if (held.has('w')) step.add(forward);
      if (held.has('s')) step.sub(forward);
      if (held.has('d')) step.add(side);
      if (held.has('a')) step.sub(side);
      if (held.has('e')) step.add(camera.up);
      if (held.has('q')) step.sub(camera.up);
      step.multiplyScalar(speed);
      camera.position.add(step);
      controls.target.add(step);
      controls.update();
      draw();
      requestAnimationFrame(walk);
    }
    window.addEventListener('keydown', (e) => {
      const k = e.key.toLowerCase();
      if (!'wasdqe'.includes(k) || k.length !== 1 || e.target.tagName === 'INPUT') return;
      if (!held.size) requestAnimationFrame(walk);
      held.add(k);
    });
    window.addEventListener('keyup', (e) => held.delete(e.key.toLowerCase()));
    window.addEventListener('blur', () => held.clear());

    controls.addEventListener('change', draw);
    for (const el of [$('ev'), $('mode'), $('edges')]) el.addEventListener('input', update);
    for (const { slider, colour } of lights) {
      slider.addEventListener('input', update);
      colour.addEventListener('input', update);
    }
    window.addEventListener('resize', resize);
    resize();
    update();
    // Milliseconds from the start of navigation to the first picture (docs/viewer.md quotes it).
    document.body.dataset.loadMs = String(Math.round(performance.now()));
    document.body.dataset.state = 'ready';
  }
})();
