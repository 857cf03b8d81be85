// The browser stand-in for the MR headset of SMP-MRO (Nakamura & Sekiyama, IEEE Access):
// it shows the scene `tamp serve` publishes, lets a person drag objects (each release is one
// demonstration step), and calls plan / execute over rosbridge (roslibjs), like a ROS# app.
// Coordinates are those of the MR frame "mr" in ROS convention (x forward, z up).
'use strict';

(function () {
  const $ = (id) => document.getElementById(id);
  const url = (location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/' +
    location.search;  // keeps ?token=...
  const ros = new ROSLIB.Ros({ url: url });
  const state = { phase: null, session: null, scene: null, steps: [], plan: null, events: [],
                  lastService: null, connected: false };

  function log(text) {
    const el = $('log');
    el.textContent = text + '\n' + el.textContent.slice(0, 20000);
  }

  ros.on('connection', () => { state.connected = true; $('link').textContent = url; });
  ros.on('error', () => { $('link').textContent = 'error (is tamp serve running?)'; });
  ros.on('close', () => { state.connected = false; $('link').textContent = 'closed'; });

  function topic(name, type, cb) {
    const t = new ROSLIB.Topic({ ros: ros, name: name, messageType: type });
    if (cb) t.subscribe(cb);
    return t;
  }
  const json = (cb) => (m) => cb(JSON.parse(m.data));

  function call(name, type, args, done) {
    const srv = new ROSLIB.Service({ ros: ros, name: name, serviceType: type });
    srv.callService(new ROSLIB.ServiceRequest(args || {}), (res) => {
      state.lastService = { name: name, res: res };
      log(name + ': ' + (res.success === false ? 'refused: ' : '') + (res.message || ''));
      if (done) done(res);
    }, (err) => {
      state.lastService = { name: name, error: String(err) };
      log(name + ': error: ' + err);
    });
  }

  // ---- 3D view (three.js core; z up) ---------------------------------------------------
  const view = $('view');
  let renderer = null;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.setClearColor(0xeef1f4);
    view.appendChild(renderer.domElement);
  } catch (e) {
    $('nogl').textContent = 'WebGL is not available: the 3D view is off (buttons still work)';
  }
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(45, 1, 0.05, 100);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.AmbientLight(0xffffff, 0.5));
  const sun = new THREE.DirectionalLight(0xffffff, 0.8);
  sun.position.set(2, -3, 6);
  scene.add(sun);
  const grid = new THREE.GridHelper(8, 16);
  grid.rotation.x = Math.PI / 2;
  scene.add(grid);
  const floor = new THREE.Plane(new THREE.Vector3(0, 0, 1), 0);
  const groups = { objects: new THREE.Object3D(), areas: new THREE.Object3D(),
                   goals: new THREE.Object3D() };
  Object.keys(groups).forEach((k) => scene.add(groups[k]));
  const robot = new THREE.Mesh(new THREE.BoxGeometry(0.5, 0.35, 0.15),
                               new THREE.MeshLambertMaterial({ color: 0xf08c2a }));
  robot.position.z = 0.075;
  scene.add(robot);
  const objects = {};  // id -> mesh

  function resize() {
    const w = view.clientWidth, h = view.clientHeight;
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
    if (renderer) renderer.setSize(w, h);
  }
  window.addEventListener('resize', resize);

  function clear(group) {
    while (group.children.length) group.remove(group.children[0]);
  }

  function ring(p, r, color) {
    const m = new THREE.Mesh(new THREE.RingGeometry(r * 0.8, r, 32),
                             new THREE.MeshBasicMaterial({ color: color, side: THREE.DoubleSide }));
    m.position.set(p[0], p[1], 0.002);
    return m;
  }

  function showScene(s) {
    state.scene = s;
    clear(groups.objects); clear(groups.areas); clear(groups.goals);
    Object.keys(objects).forEach((k) => delete objects[k]);
    const xs = [], ys = [];
    s.objects.forEach((o) => {
      const m = new THREE.Mesh(new THREE.CylinderGeometry(0.05, 0.05, 0.2, 20),
                               new THREE.MeshLambertMaterial({ color: 0x2a7ff0 }));
      m.rotation.x = Math.PI / 2;  // the cylinder's axis along z
      m.position.set(o.mr[0], o.mr[1], 0.1);
      m.userData = { id: o.id, start: o.mr.slice() };
      groups.objects.add(m);
      objects[o.id] = m;
      groups.areas.add(ring(o.mr, s.area_radius, 0x9aa5b1));
      xs.push(o.mr[0]); ys.push(o.mr[1]);
    });
    s.free_areas.forEach((a) => {
      groups.areas.add(ring(a.mr, s.area_radius, 0x3cb371));
      xs.push(a.mr[0]); ys.push(a.mr[1]);
    });
    robot.position.set(s.robot_mr[0], s.robot_mr[1], 0.075);
    robot.rotation.z = s.robot_yaw || 0;
    xs.push(s.robot_mr[0]); ys.push(s.robot_mr[1]);
    const cx = (Math.min(...xs) + Math.max(...xs)) / 2, cy = (Math.min(...ys) + Math.max(...ys)) / 2;
    const span = Math.max(Math.max(...xs) - Math.min(...xs), Math.max(...ys) - Math.min(...ys), 2);
    grid.position.set(cx, cy, 0);
    camera.position.set(cx - 0.3 * span, cy - 1.4 * span, 1.6 * span);
    camera.lookAt(new THREE.Vector3(cx, cy, 0));
  }

  function showSteps(doc) {
    state.steps = doc.steps;
    $('steps').textContent = doc.steps.length;
    const last = {};
    doc.steps.forEach((s) => { last[s.object] = s.mr; });
    if (state.scene) {
      state.scene.objects.forEach((o) => {
        const p = last[o.id] || o.mr, m = objects[o.id];
        if (m && m !== dragging) m.position.set(p[0], p[1], 0.1);
      });
    }
    clear(groups.goals);
    doc.steps.forEach((s) => groups.goals.add(ring(s.mr, 0.12, 0xd04060)));
  }

  topic('/tamp/scene', 'std_msgs/String', json(showScene));
  topic('/tamp/demo/steps', 'std_msgs/String', json(showSteps));
  topic('/tamp/state', 'std_msgs/String', json((s) => {
    state.phase = s.phase; state.session = s.session;
    $('phase').textContent = s.phase;
    $('session').textContent = s.session ? '(' + s.session + (s.run ? ', ' + s.run : '') + ')' : '';
  }));
  topic('/tamp/plan_result', 'std_msgs/String', json((p) => {
    state.plan = p;
    $('order').textContent = p.success ? p.message : (p.message || '–');
  }));
  topic('/tamp/bt', 'std_msgs/String', json((b) => {
    $('bt').textContent = b.running ? 'running ' + b.running :
      (b.status ? b.status + ', ' + b.goals_reached + ' goals, tree ' + b.tree_size + ' nodes' : '–');
  }));
  topic('/tamp/events', 'std_msgs/String', json((e) => {
    state.events.push(e);
    log(e.kind + (e.what ? ' ' + e.what : '') + (e.condition ? ' ' + e.condition : '') + (e.why ? ': ' + e.why : '') + (e.tick !== undefined ? '  [tick ' + e.tick + ']' : ''));
  }));
  topic('/tamp/execution', 'std_msgs/String', json((x) => {
    state.execution = { run: x.run, reached: x.reached, executed: x.executed };
    Object.keys(x.final_mr || {}).forEach((id) => {
      const m = objects[id], p = x.final_mr[id];
      if (m) m.position.set(p[0], p[1], 0.1);
    });
  }));
  topic('/tamp/robot/pose', 'geometry_msgs/PoseStamped', (m) => {
    const p = m.pose.position, q = m.pose.orientation;
    robot.position.set(p.x, p.y, 0.075);
    robot.rotation.z = 2 * Math.atan2(q.z, q.w);
  });
  const stepTopic = topic('/tamp/demo/step', 'tamp_msgs/DemoStep');

  function sendStep(id, p) {
    stepTopic.publish(new ROSLIB.Message({
      header: { frame_id: 'mr' }, object_id: id,
      pose: { position: { x: p[0], y: p[1], z: p[2] || 0 },
              orientation: { x: 0, y: 0, z: 0, w: 1 } } }));
  }

  // ---- drag: three.js DragControls; the object follows the pointer's ray onto the floor -
  const raycaster = new THREE.Raycaster();
  let dragging = null;
  let lastPointer = null;
  function floorPoint(ev) {
    const r = renderer.domElement.getBoundingClientRect();
    const v = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1,
                                -((ev.clientY - r.top) / r.height) * 2 + 1);
    raycaster.setFromCamera(v, camera);
    return raycaster.ray.intersectPlane(floor, new THREE.Vector3());
  }
  if (renderer) {
    renderer.domElement.addEventListener('pointermove', (ev) => { lastPointer = ev; });
    const controls = new THREE.DragControls(groups.objects.children, camera, renderer.domElement);
    controls.addEventListener('dragstart', (e) => { dragging = e.object; });
    controls.addEventListener('drag', (e) => {
      const p = lastPointer && floorPoint(lastPointer);
      if (p) e.object.position.set(p.x, p.y, 0.1); else e.object.position.z = 0.1;
    });
    controls.addEventListener('dragend', (e) => {
      dragging = null;
      const m = e.object;
      const p = [Math.round(m.position.x * 1000) / 1000, Math.round(m.position.y * 1000) / 1000, 0];
      sendStep(m.userData.id, p);
    });
  }

  // ---- buttons -------------------------------------------------------------------------
  const TRIGGER = 'std_srvs/Trigger';
  $('open').onclick = () => call('/tamp/demo/open', 'tamp_msgs/OpenDemo', { name: $('case').value });
  $('undo').onclick = () => call('/tamp/demo/undo', TRIGGER);
  $('reset').onclick = () => call('/tamp/demo/reset', TRIGGER);
  $('export').onclick = () => call('/tamp/demo/export', TRIGGER, {}, (r) => {
    if (r.success) log(r.message);
  });
  $('plan').onclick = () => call('/tamp/plan', 'tamp_msgs/Plan',
                                 { cost_model: $('cost').value, constraints: [] });
  $('execute').onclick = () => call('/tamp/execute', TRIGGER);
  $('cancel').onclick = () => call('/tamp/cancel', TRIGGER);

  function frame() {
    if (renderer) renderer.render(scene, camera);
    requestAnimationFrame(frame);
  }
  resize();
  frame();

  // Hooks for scripts and tests: the same messages the mouse sends.
  window.demo = {
    state: state,
    drag: (id, p) => sendStep(id, p),
    objectScreen: (id) => {  // where an object is drawn, in page pixels
      const m = objects[id];
      if (!m || !renderer) return null;
      camera.updateMatrixWorld();  // the camera may have moved since the last frame
      const v = m.position.clone().project(camera), r = renderer.domElement.getBoundingClientRect();
      return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
    },
    objectPosition: (id) => objects[id] ? [objects[id].position.x, objects[id].position.y] : null,
    webgl: !!renderer,
  };
})();
