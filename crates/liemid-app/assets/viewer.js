// The liemid viewer: reads the page's inlined data and three.js (as text), loads three.js
// as modules from blob URLs (nothing leaves the page) and animates the run.
(function () {
  'use strict';
  const $ = (id) => document.getElementById(id);
  const meta = JSON.parse($('meta').textContent);

  function fail(e) {
    const p = document.createElement('p');
    p.id = 'error';
    p.textContent = 'The viewer could not start: ' + (e && e.message ? e.message : e);
    $('panel').appendChild(p);
    document.body.dataset.error = String(e);
  }

  // Base64 of little-endian float32 into a Float32Array.
  function floats(id) {
    const s = atob($(id).textContent.trim());
    const bytes = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) bytes[i] = s.charCodeAt(i);
    const n = bytes.length >> 2;
    const little = new Uint8Array(new Float32Array([1]).buffer)[3] === 0x3f;
    if (little) return new Float32Array(bytes.buffer, 0, n);
    const view = new DataView(bytes.buffer);
    const out = new Float32Array(n);
    for (let i = 0; i < n; i++) out[i] = view.getFloat32(4 * i, true);
    return out;
  }

  const url = (s) => URL.createObjectURL(new Blob([s], { type: 'text/javascript' }));
  let modules;
  try {
    const core = url($('three-core').textContent);
    const three = url($('three-module').textContent.split('"./three.core.min.js"').join(JSON.stringify(core)));
    const orbit = url($('three-orbit').textContent.replace(/from\s*['"]three['"]/g, 'from ' + JSON.stringify(three)));
    modules = Promise.all([import(three), import(orbit)]);
  } catch (e) {
    fail(e);
    return;
  }
  modules.then(([THREE, orbit]) => start(THREE, orbit.OrbitControls)).catch(fail);

  function start(THREE, OrbitControls) {
    const F = meta.frames, P = meta.per_frame, sc = meta.scene;
    const frames = floats('data-frames'), times = floats('data-times'), energy = floats('data-energy'), stat = floats('data-static');
    $('caption').textContent = meta.caption;
    const stage = $('stage');
    const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    stage.appendChild(renderer.domElement);
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0x20242d);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x445066, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.8);
    sun.position.set(3, 5, 4);
    scene.add(sun);
    const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 1e5);
    const controls = new OrbitControls(camera, renderer.domElement);
    controls.enableDamping = true;

    const yAxis = new THREE.Vector3(0, 1, 0);
    const tmpQ = new THREE.Quaternion(), tmpV = new THREE.Vector3(), tmpM = new THREE.Matrix4();
    const one = new THREE.Vector3(1, 1, 1);
    const quat = (f, k) => tmpQ.set(f[k + 1], f[k + 2], f[k + 3], f[k]);
    const coolWarm = (c, v) => {
      // -1 blue, 0 white, +1 red.
      const s = Math.max(-1, Math.min(1, v));
      return s < 0 ? c.setRGB(1 + s * 0.8, 1 + s * 0.6, 1) : c.setRGB(1, 1 - s * 0.6, 1 - s * 0.8);
    };

    let view;
    if (sc.kind === 'rigid_body') view = rigidBody();
    else if (sc.kind === 'bodies') view = bodies();
    else if (sc.kind === 'beam') view = beam();
    else if (sc.kind === 'spins') view = spins();
    else if (sc.kind === 'articulated') view = articulated();
    else throw new Error('unknown scene ' + sc.kind);

    function rigidBody() {
      const [a, b, c] = sc.half_extents;
      const body = new THREE.Group();
      body.matrixAutoUpdate = false;
      const geometry = new THREE.BoxGeometry(2 * a, 2 * b, 2 * c);
      body.add(new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: 0x7f9cc4, roughness: 0.55, metalness: 0.1 })));
      body.add(new THREE.LineSegments(new THREE.EdgesGeometry(geometry), new THREE.LineBasicMaterial({ color: 0x1b2330 })));
      const colours = [0xe0524c, 0x4cc46a, 0x4c8ee0];
      for (let i = 0; i < 3; i++) {
        const d = new THREE.Vector3(i === 0, i === 1, i === 2);
        body.add(new THREE.ArrowHelper(d, new THREE.Vector3(), 1.6 * [a, b, c][i] + 0.3, colours[i], 0.15, 0.08));
      }
      scene.add(body);
      let lmax = 1e-300;
      for (let i = 0; i < F; i++) lmax = Math.max(lmax, Math.hypot(frames[12 * i + 9], frames[12 * i + 10], frames[12 * i + 11]));
      const l = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1.8, 0xf2c744, 0.2, 0.1);
      scene.add(l);
      scene.add(new THREE.GridHelper(4, 8, 0x3b4352, 0x2c3340).translateY(-1.9));
      return {
        radius: 2.2,
        centre: new THREE.Vector3(),
        update(i) {
          const f = frames.subarray(12 * i, 12 * i + 12);
          body.matrix.set(f[0], f[1], f[2], 0, f[3], f[4], f[5], 0, f[6], f[7], f[8], 0, 0, 0, 0, 1);
          body.matrixWorldNeedsUpdate = true;
          const n = Math.hypot(f[9], f[10], f[11]);
          if (n > 0) {
            l.setDirection(tmpV.set(f[9] / n, f[10] / n, f[11] / n));
            l.setLength(0.4 + 1.6 * n / lmax, 0.2, 0.1);
          }
        },
      };
    }

    // An InstancedMesh of cones pointing along +y, one per item.
    function arrows(count, length) {
      const geometry = new THREE.ConeGeometry(0.22 * length, length, 10);
      const mesh = new THREE.InstancedMesh(geometry, new THREE.MeshStandardMaterial({ roughness: 0.5 }), count);
      mesh.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(3 * count), 3);
      mesh.frustumCulled = false;
      scene.add(mesh);
      return mesh;
    }

    function bodies() {
      const n = sc.count, L = sc.box_length;
      const mesh = arrows(n, sc.length);
      const axis = new THREE.Vector3(...sc.axis).normalize();
      const align = new THREE.Quaternion().setFromUnitVectors(yAxis, axis);
      const colour = new THREE.Color(), pos = new THREE.Vector3(), q = new THREE.Quaternion();
      // Bodies about fixed pivots all sit at one point: lay them out on a grid.
      let spread = 0;
      for (let j = 1; j < n; j++) spread = Math.max(spread, Math.abs(frames[7 * j] - frames[0]), Math.abs(frames[7 * j + 1] - frames[1]));
      const side = Math.ceil(Math.cbrt(n)), grid = !L && spread < 1e-6;
      const gap = 1.6 * sc.length;
      let radius, centre;
      if (L) {
        const edges = new THREE.LineSegments(new THREE.EdgesGeometry(new THREE.BoxGeometry(L, L, L)), new THREE.LineBasicMaterial({ color: 0x8896ab }));
        edges.position.set(L / 2, L / 2, L / 2);
        scene.add(edges);
        radius = 0.9 * L;
        centre = new THREE.Vector3(L / 2, L / 2, L / 2);
      } else if (grid) {
        radius = 0.9 * side * gap;
        centre = new THREE.Vector3(1, 1, 1).multiplyScalar((side - 1) * gap / 2);
      } else {
        const box = new THREE.Box3();
        for (let j = 0; j < n; j++) box.expandByPoint(tmpV.set(frames[7 * j], frames[7 * j + 1], frames[7 * j + 2]));
        centre = box.getCenter(new THREE.Vector3());
        radius = Math.max(box.getSize(tmpV).length() / 2, 2 * sc.length);
      }
      const wrap = (x) => x - L * Math.floor(x / L);
      return {
        radius,
        centre,
        update(i) {
          const f = frames.subarray(P * i, P * i + P);
          for (let j = 0; j < n; j++) {
            const k = 7 * j;
            if (grid) pos.set((j % side) * gap, (Math.floor(j / side) % side) * gap, Math.floor(j / (side * side)) * gap);
            else if (L) pos.set(wrap(f[k]), wrap(f[k + 1]), wrap(f[k + 2]));
            else pos.set(f[k], f[k + 1], f[k + 2]);
            q.copy(quat(f, k + 3)).multiply(align);
            tmpM.compose(pos, q, one);
            mesh.setMatrixAt(j, tmpM);
            tmpV.copy(axis).applyQuaternion(quat(f, k + 3));
            mesh.setColorAt(j, coolWarm(colour, tmpV.z));
          }
          mesh.instanceMatrix.needsUpdate = true;
          mesh.instanceColor.needsUpdate = true;
        },
      };
    }

    function beam() {
      const n = sc.nodes, E = stat.length / 2;
      const box = new THREE.Box3();
      for (let j = 0; j < n; j++) box.expandByPoint(tmpV.set(frames[7 * j], frames[7 * j + 1], frames[7 * j + 2]));
      const size = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-9);
      const line = new THREE.BufferGeometry();
      line.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6 * E), 3));
      scene.add(new THREE.LineSegments(line, new THREE.LineBasicMaterial({ color: 0xf0f0f0 })));
      const triads = new THREE.BufferGeometry();
      const tp = new Float32Array(18 * n), tc = new Float32Array(18 * n);
      const rgb = [[0.9, 0.3, 0.3], [0.3, 0.8, 0.4], [0.3, 0.55, 0.9]];
      for (let j = 0; j < n; j++) for (let a = 0; a < 3; a++) for (let e = 0; e < 2; e++) tc.set(rgb[a], 18 * j + 6 * a + 3 * e);
      triads.setAttribute('position', new THREE.BufferAttribute(tp, 3));
      triads.setAttribute('color', new THREE.BufferAttribute(tc, 3));
      scene.add(new THREE.LineSegments(triads, new THREE.LineBasicMaterial({ vertexColors: true })));
      const dots = new THREE.InstancedMesh(new THREE.SphereGeometry(0.008 * size, 8, 6), new THREE.MeshStandardMaterial({ color: 0xd8c27a }), n);
      dots.frustumCulled = false;
      scene.add(dots);
      const len = 0.06 * size;
      const axes = [new THREE.Vector3(1, 0, 0), new THREE.Vector3(0, 1, 0), new THREE.Vector3(0, 0, 1)];
      return {
        radius: 0.7 * size,
        centre: box.getCenter(new THREE.Vector3()),
        update(i) {
          const f = frames.subarray(P * i, P * i + P);
          const p = line.attributes.position.array;
          for (let e = 0; e < E; e++) {
            for (let s = 0; s < 2; s++) {
              const k = 7 * stat[2 * e + s];
              p.set([f[k], f[k + 1], f[k + 2]], 6 * e + 3 * s);
            }
          }
          line.attributes.position.needsUpdate = true;
          for (let j = 0; j < n; j++) {
            const k = 7 * j;
            quat(f, k + 3);
            for (let a = 0; a < 3; a++) {
              tmpV.copy(axes[a]).applyQuaternion(tmpQ).multiplyScalar(len);
              tp.set([f[k], f[k + 1], f[k + 2], f[k] + tmpV.x, f[k + 1] + tmpV.y, f[k + 2] + tmpV.z], 18 * j + 6 * a);
            }
            dots.setMatrixAt(j, tmpM.makeTranslation(f[k], f[k + 1], f[k + 2]));
          }
          triads.attributes.position.needsUpdate = true;
          dots.instanceMatrix.needsUpdate = true;
        },
      };
    }

    function spins() {
      const n = stat.length / 3;
      const mesh = arrows(n, 0.85);
      const box = new THREE.Box3();
      for (let j = 0; j < n; j++) box.expandByPoint(tmpV.set(stat[3 * j], stat[3 * j + 1], stat[3 * j + 2]));
      const colour = new THREE.Color(), pos = new THREE.Vector3(), q = new THREE.Quaternion();
      return {
        radius: Math.max(0.6 * box.getSize(new THREE.Vector3()).length(), 2),
        centre: box.getCenter(new THREE.Vector3()),
        update(i) {
          const f = frames.subarray(P * i, P * i + P);
          for (let j = 0; j < n; j++) {
            const k = 3 * j;
            tmpV.set(f[k], f[k + 1], f[k + 2]);
            const norm = tmpV.length() || 1;
            q.setFromUnitVectors(yAxis, tmpV.multiplyScalar(1 / norm));
            pos.set(stat[k], stat[k + 1], stat[k + 2]);
            tmpM.compose(pos, q, one);
            mesh.setMatrixAt(j, tmpM);
            mesh.setColorAt(j, coolWarm(colour, f[k + 2] / norm));
          }
          mesh.instanceMatrix.needsUpdate = true;
          mesh.instanceColor.needsUpdate = true;
        },
      };
    }

    // The meshes of the page (`data-meshes`: each mesh's vertices, then its triangles'
    // indices), flat-shaded geometries shared by the shapes that draw them.
    function meshGeometries() {
      const counts = sc.meshes || [];
      if (!counts.length) return [];
      const data = floats('data-meshes');
      let at = 0;
      return counts.map(([nv, nt]) => {
        const position = data.slice(at, at + 3 * nv);
        at += 3 * nv;
        const index = new Uint32Array(3 * nt);
        for (let i = 0; i < 3 * nt; i++) index[i] = data[at + i];
        at += 3 * nt;
        const indexed = new THREE.BufferGeometry();
        indexed.setAttribute('position', new THREE.BufferAttribute(position, 3));
        indexed.setIndex(new THREE.BufferAttribute(index, 1));
        const g = indexed.toNonIndexed();
        g.computeVertexNormals();
        return g;
      });
    }

    // A model's shape (MuJoCo's conventions: capsules and cylinders along z, planes normal
    // to z) as a three.js object; a mesh's size is the scale of its coordinates.
    function shapeObject(sh, geometries) {
      const [a, b, c] = sh.size;
      const [r, gc, bl, alpha] = sh.rgba;
      const material = new THREE.MeshStandardMaterial({ color: new THREE.Color(r, gc, bl), roughness: 0.6, transparent: alpha < 1, opacity: alpha });
      const alongZ = (geometry) => geometry.rotateX(Math.PI / 2);
      let object;
      if (sh.kind === 'plane') {
        const extent = a > 0 ? 2 * Math.max(a, b) : 20;
        object = new THREE.Group();
        const floor = new THREE.Mesh(new THREE.PlaneGeometry(a > 0 ? 2 * a : extent, b > 0 ? 2 * b : extent), material);
        material.side = THREE.DoubleSide;
        material.transparent = true;
        material.opacity = Math.min(alpha, 0.85);
        object.add(floor);
        const grid = new THREE.GridHelper(extent, Math.max(2, Math.round(extent / 0.5)), 0x8a93a3, 0x4a5263);
        grid.rotateX(Math.PI / 2);
        grid.position.z = 1e-3 * extent;
        object.add(grid);
      } else if (sh.kind === 'sphere') object = new THREE.Mesh(new THREE.SphereGeometry(a, 24, 16), material);
      else if (sh.kind === 'capsule') object = new THREE.Mesh(alongZ(new THREE.CapsuleGeometry(a, 2 * b, 8, 16)), material);
      else if (sh.kind === 'cylinder') object = new THREE.Mesh(alongZ(new THREE.CylinderGeometry(a, a, 2 * b, 24)), material);
      else if (sh.kind === 'box') object = new THREE.Mesh(new THREE.BoxGeometry(2 * a, 2 * b, 2 * c), material);
      else if (sh.kind === 'mesh') {
        material.side = THREE.DoubleSide;
        object = new THREE.Mesh(geometries[sh.mesh], material);
        object.scale.set(a, b, c);
      } else {
        object = new THREE.Mesh(new THREE.SphereGeometry(1, 24, 16), material);
        object.scale.set(a, b, c);
      }
      object.position.set(...sh.position);
      object.quaternion.set(sh.quaternion[1], sh.quaternion[2], sh.quaternion[3], sh.quaternion[0]);
      return object;
    }

    // A checkbox in the panel that shows or hides `objects`.
    function toggle(text, objects, on) {
      const label = document.createElement('label');
      const box = document.createElement('input');
      box.type = 'checkbox';
      box.checked = on;
      const set = () => objects.forEach((o) => { o.visible = box.checked; });
      box.onchange = set;
      set();
      label.append(box, ' ' + text);
      $('panel').appendChild(label);
      return box;
    }

    function articulated() {
      const n = stat.length / 3, joints = sc.joints, shapes = sc.shapes || [];
      const mesh = new THREE.InstancedMesh(new THREE.BoxGeometry(2, 2, 2), new THREE.MeshStandardMaterial({ color: 0x7f9cc4, roughness: 0.55 }), n);
      mesh.frustumCulled = false;
      scene.add(mesh);
      const lines = new THREE.BufferGeometry();
      lines.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6 * joints.length), 3));
      const jointLines = new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: 0xf2c744 }));
      scene.add(jointLines);
      // The model's shapes: one group per body, moved with its centre of mass; the world's
      // shapes (a floor) stay.
      const groups = [];
      for (let j = 0; j < n; j++) {
        const group = new THREE.Group();
        group.matrixAutoUpdate = false;
        scene.add(group);
        groups.push(group);
      }
      const drawn = new Array(n).fill(false);
      const geometries = meshGeometries();
      shapes.forEach((sh) => {
        const object = shapeObject(sh, geometries);
        if (sh.body === null || sh.body === undefined) scene.add(object);
        else {
          groups[sh.body].add(object);
          drawn[sh.body] = true;
        }
      });
      // A body the file draws nothing of (its meshes missing) keeps its box of inertia;
      // the others' boxes and the joints are shown on request.
      let allBoxes = true;
      if (shapes.length) {
        const boxes = toggle('boxes of inertia of every body', [], false);
        allBoxes = false;
        boxes.addEventListener('change', () => { allBoxes = boxes.checked; shown = -1; });
        toggle('joints', [jointLines], false);
        toggle("the model's shapes", groups, true);
        document.body.dataset.shapes = String(shapes.length);
      }
      const box = new THREE.Box3();
      for (let j = 0; j < n; j++) box.expandByPoint(tmpV.set(frames[7 * j], frames[7 * j + 1], frames[7 * j + 2]));
      let ext = 0;
      for (let j = 0; j < stat.length; j++) ext = Math.max(ext, stat[j]);
      // The touching contacts after the bodies in each frame: a red point each and its
      // force on the first body as a red line, the largest force of the run a fifth of the
      // view's size.
      const slots = sc.contact_slots || 0, C = 7 * n;
      let contactPoints = null, contactLines = null, fmax = 0;
      if (slots > 0) {
        for (let i = 0; i < F; i++) {
          for (let c = 0; c < slots; c++) {
            const k = P * i + C + 6 * c;
            if (Number.isNaN(frames[k])) break;
            fmax = Math.max(fmax, Math.hypot(frames[k + 3], frames[k + 4], frames[k + 5]));
          }
        }
        const pts = new THREE.BufferGeometry();
        pts.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * slots), 3));
        contactPoints = new THREE.Points(pts, new THREE.PointsMaterial({ color: 0xe03030, size: 6, sizeAttenuation: false, depthTest: false }));
        const segs = new THREE.BufferGeometry();
        segs.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6 * slots), 3));
        contactLines = new THREE.LineSegments(segs, new THREE.LineBasicMaterial({ color: 0xe03030, depthTest: false }));
        contactPoints.frustumCulled = false;
        contactLines.frustumCulled = false;
        // Drawn over the bodies: a contact is under or inside them.
        contactPoints.renderOrder = contactLines.renderOrder = 1;
        scene.add(contactPoints, contactLines);
        toggle('contact points and forces', [contactPoints, contactLines], true);
        document.body.dataset.contacts = String(slots);
      }
      const pos = new THREE.Vector3(), scale = new THREE.Vector3();
      const anchor = (f, body, a) => {
        if (body === null || body === undefined) return tmpV.set(...a);
        const k = 7 * body;
        return tmpV.set(...a).applyQuaternion(quat(f, k + 3)).add(pos.set(f[k], f[k + 1], f[k + 2]));
      };
      const radius = Math.max(0.8 * box.getSize(new THREE.Vector3()).length(), 4 * ext, 1);
      const forceScale = fmax > 0 ? 0.2 * radius / fmax : 0;
      return {
        radius,
        centre: box.getCenter(new THREE.Vector3()),
        zUp: true,
        update(i) {
          const f = frames.subarray(P * i, P * i + P);
          if (slots > 0) {
            const pp = contactPoints.geometry.attributes.position.array, lp = contactLines.geometry.attributes.position.array;
            let m = 0;
            for (; m < slots; m++) {
              const k = C + 6 * m;
              if (Number.isNaN(f[k])) break;
              pp[3 * m] = f[k]; pp[3 * m + 1] = f[k + 1]; pp[3 * m + 2] = f[k + 2];
              lp[6 * m] = f[k]; lp[6 * m + 1] = f[k + 1]; lp[6 * m + 2] = f[k + 2];
              lp[6 * m + 3] = f[k] + forceScale * f[k + 3];
              lp[6 * m + 4] = f[k + 1] + forceScale * f[k + 4];
              lp[6 * m + 5] = f[k + 2] + forceScale * f[k + 5];
            }
            contactPoints.geometry.setDrawRange(0, m);
            contactLines.geometry.setDrawRange(0, 2 * m);
            contactPoints.geometry.attributes.position.needsUpdate = true;
            contactLines.geometry.attributes.position.needsUpdate = true;
            document.body.dataset.touching = String(m);
          }
          for (let j = 0; j < n; j++) {
            const k = 7 * j;
            pos.set(f[k], f[k + 1], f[k + 2]);
            if (allBoxes || !drawn[j]) scale.set(stat[3 * j], stat[3 * j + 1], stat[3 * j + 2]);
            else scale.set(0, 0, 0);
            mesh.setMatrixAt(j, tmpM.compose(pos, quat(f, k + 3), scale));
            groups[j].matrix.compose(pos, quat(f, k + 3), one);
          }
          mesh.instanceMatrix.needsUpdate = true;
          const p = lines.attributes.position.array;
          joints.forEach((jt, m) => {
            p.set(anchor(f, jt.parent, jt.parent_anchor).toArray(), 6 * m);
            p.set(anchor(f, jt.child, jt.child_anchor).toArray(), 6 * m + 3);
          });
          lines.attributes.position.needsUpdate = true;
        },
      };
    }

    // Camera and size.
    const r = view.radius;
    const flat = sc.kind === 'spins' && stat.every((v, k) => k % 3 !== 2 || v === 0);
    if (view.zUp) {
      // Model files (MJCF, URDF) put z up.
      camera.up.set(0, 0, 1);
      camera.position.copy(view.centre).add(new THREE.Vector3(1.6 * r, -1.4 * r, 0.9 * r));
    } else {
      camera.up.set(0, flat ? 0 : 1, flat ? 1 : 0);
      camera.position.copy(view.centre).add(flat ? new THREE.Vector3(0, -0.9 * r, 2.0 * r) : new THREE.Vector3(1.5 * r, 1.0 * r, 1.9 * r));
    }
    camera.near = 0.01 * r;
    camera.far = 100 * r;
    controls.target.copy(view.centre);
    function resize() {
      const w = stage.clientWidth, h = stage.clientHeight;
      renderer.setSize(w, h);
      camera.aspect = w / Math.max(h, 1);
      camera.updateProjectionMatrix();
    }
    window.addEventListener('resize', resize);
    resize();

    // The energy panel.
    const plot = $('energy'), g = plot.getContext('2d');
    const E = energy.length / 2;
    let tMin = Infinity, tMax = -Infinity, eMin = Infinity, eMax = -Infinity;
    for (let k = 0; k < E; k++) {
      tMin = Math.min(tMin, energy[2 * k]); tMax = Math.max(tMax, energy[2 * k]);
      eMin = Math.min(eMin, energy[2 * k + 1]); eMax = Math.max(eMax, energy[2 * k + 1]);
    }
    if (F > 0) { tMin = Math.min(tMin, times[0]); tMax = Math.max(tMax, times[F - 1]); }
    if (!(eMax > eMin)) { eMin -= 1e-16; eMax += 1e-16; }
    const pad = { l: 58, r: 8, t: 20, b: 24 };
    const X = (t) => pad.l + (plot.width - pad.l - pad.r) * (tMax > tMin ? (t - tMin) / (tMax - tMin) : 0);
    const Y = (e) => plot.height - pad.b - (plot.height - pad.t - pad.b) * (e - eMin) / (eMax - eMin);
    function drawEnergy(t) {
      g.clearRect(0, 0, plot.width, plot.height);
      g.font = '11px system-ui, sans-serif';
      g.fillStyle = '#98a2b3';
      g.fillText(meta.energy_label + (E ? '' : ': not recorded'), pad.l, 13);
      g.strokeStyle = '#2c3340';
      g.strokeRect(pad.l, pad.t, plot.width - pad.l - pad.r, plot.height - pad.t - pad.b);
      if (E) {
        g.fillText(eMax.toExponential(1), 2, pad.t + 8);
        g.fillText(eMin.toExponential(1), 2, plot.height - pad.b);
        g.fillText('t = ' + tMin.toPrecision(3), pad.l, plot.height - 8);
        g.fillText(tMax.toPrecision(3), plot.width - pad.r - 40, plot.height - 8);
        g.strokeStyle = '#6fb3ff';
        g.beginPath();
        for (let k = 0; k < E; k++) {
          const x = X(energy[2 * k]), y = Y(energy[2 * k + 1]);
          if (k) g.lineTo(x, y); else g.moveTo(x, y);
        }
        g.stroke();
      }
      g.strokeStyle = '#f2c744';
      g.beginPath();
      g.moveTo(X(t), pad.t);
      g.lineTo(X(t), plot.height - pad.b);
      g.stroke();
    }

    // Playback: the whole run in about 12 s at speed 1.
    const slider = $('slider'), play = $('play'), speed = $('speed'), label = $('time'), readout = $('readout');
    const rate = Math.max(F / 12, 1);
    let pos = 0, playing = F > 1, shown = -1, last = null, count = 0, since = null;
    // `#frame=N` opens the page at frame N (a link to a moment of the run; the browser test).
    const asked = /frame=(\d+)/.exec(location.hash);
    if (asked) pos = Math.min(Math.max(F - 1, 0), Number(asked[1]));
    play.textContent = playing ? 'pause' : 'play';
    play.onclick = () => { playing = !playing; play.textContent = playing ? 'pause' : 'play'; };
    slider.oninput = () => { pos = Number(slider.value); };
    plot.onclick = (ev) => {
      const t = tMin + (tMax - tMin) * (ev.offsetX - pad.l) / (plot.width - pad.l - pad.r);
      let k = 0;
      while (k + 1 < F && times[k + 1] <= t) k++;
      pos = k;
    };
    function show(i) {
      view.update(i);
      shown = i;
      slider.value = String(i);
      const t = times[i];
      label.textContent = 't = ' + t.toPrecision(5) + '  (' + (i + 1) + ' / ' + F + ')';
      let k = 0;
      while (k + 1 < E && energy[2 * k + 2] <= t) k++;
      readout.textContent = E ? meta.energy_label + ' at t: ' + energy[2 * k + 1].toExponential(3) : '';
      drawEnergy(t);
      document.body.dataset.frame = String(i);
    }
    function tick(now) {
      if (last !== null && playing) pos = (pos + (now - last) / 1000 * rate * Number(speed.value)) % F;
      last = now;
      const i = Math.min(F - 1, Math.floor(pos));
      if (F > 0 && i !== shown) show(i);
      controls.update();
      renderer.render(scene, camera);
      count++;
      if (since === null) since = now;
      if (now - since >= 1000) {
        const fps = (1000 * count) / (now - since);
        $('fps').textContent = fps.toFixed(1) + ' frames/s drawn';
        document.body.dataset.fps = fps.toFixed(1);
        count = 0;
        since = now;
      }
      document.body.dataset.rendered = String(Number(document.body.dataset.rendered || 0) + 1);
      requestAnimationFrame(tick);
    }
    requestAnimationFrame(tick);
  }
})();
