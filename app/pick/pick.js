// The page of `ema pick` (docs/pick.md): draws the stabilisation diagram, the FRFs, the mode table
// and the MAC from the server's JSON, and turns clicks into picks. Every request carries the
// page's token (read from its own URL) in the X-Ema-Token header.
//
// window.emaPick is the page's API (the tests drive it; a user may too, from the console):
//   toggle(f, zeta)  picks the pole at f Hz, or removes the picked mode whose column holds it
//   select([f...])   picks exactly these frequencies;  auto()  the automatic selection
//   save(), done()   as the buttons;  state(), fixed()  the server's last JSON
//   polePoint(i)     client coordinates of diagram pole i (for a real mouse click)
//   ready, redraws, lastRedrawMs  (body data-ready, data-redraws as well)
(function () {
  'use strict';
  var token = new URLSearchParams(location.search).get('token') || '';
  var body = document.body;
  var fixed = null;
  var state = null;
  var dirty = false;          // picked since the last Save
  var doneAsked = false;      // Done clicked once with an unsaved pick
  var queue = Promise.resolve();
  var plotConfig = { responsive: true, displaylogo: false };
  var api = window.emaPick = { ready: false, redraws: 0, lastRedrawMs: null, errors: [] };

  function $(id) { return document.getElementById(id); }
  function noteError(message) {
    api.errors.push(String(message));
    body.setAttribute('data-errors', api.errors.join(' | '));
  }
  window.addEventListener('error', function (e) { noteError(e.message || e); });
  window.addEventListener('unhandledrejection', function (e) { noteError(e.reason || 'promise rejected'); });

  function status(text, isError) {
    var s = $('status');
    s.textContent = text;
    s.className = isError ? 'error' : '';
  }
  function fmt(v, digits) { return v === null || v === undefined || !isFinite(v) ? '–' : Number(v).toFixed(digits); }
  function sigma(v) { return v === null || v === undefined || !isFinite(v) ? '' : ' ± ' + Number(v).toPrecision(2); }

  function request(method, path, payload) {
    var init = { method: method, cache: 'no-store', headers: { 'X-Ema-Token': token } };
    if (payload !== undefined) {
      init.headers['Content-Type'] = 'application/json';
      init.body = JSON.stringify(payload);
    }
    return fetch(path, init).then(function (r) {
      return r.json().catch(function () { return { error: 'HTTP ' + r.status }; }).then(function (j) {
        if (!r.ok) throw new Error(j.error || 'HTTP ' + r.status);
        return j;
      });
    });
  }

  // ---- drawing ----

  var poleStyle = {
    stable: { symbol: 'circle', color: '#1b7837', size: 7 },
    'partly stable': { symbol: 'diamond-open', color: '#4393c3', size: 6 },
    unstable: { symbol: 'circle-open', color: '#d6604d', size: 6 },
    'non-physical': { symbol: 'x-thin-open', color: '#999999', size: 5 }
  };
  function poleClass(label) {
    return label === 's' ? 'stable' : label === 'x' ? 'non-physical' : label === 'o' ? 'unstable' : 'partly stable';
  }
  function stabTraces() {
    var d = fixed.diagram, groups = {};
    for (var i = 0; i < d.order.length; i++) {
      var key = poleClass(d.label[i]);
      var g = groups[key] = groups[key] || { x: [], y: [], text: [], customdata: [] };
      g.x.push(d.frequency_hz[i]);
      g.y.push(d.order[i]);
      g.customdata.push(i);
      g.text.push('order ' + d.order[i] + '<br>' + fmt(d.frequency_hz[i], 3) + ' Hz<br>ζ ' +
        fmt(100 * d.damping_ratio[i], 3) + ' %<br>' + d.label[i]);
    }
    var traces = ['stable', 'partly stable', 'unstable', 'non-physical'].filter(function (k) { return groups[k]; })
      .map(function (k) {
        return { type: 'scatter', mode: 'markers', name: k, x: groups[k].x, y: groups[k].y, text: groups[k].text,
          customdata: groups[k].customdata, meta: 'poles', hoverinfo: 'text', cliponaxis: false,
          marker: { symbol: poleStyle[k].symbol, color: poleStyle[k].color, size: poleStyle[k].size } };
      });
    var picked = { x: [], y: [], text: [] };
    (state.modes || []).forEach(function (m, k) {
      if (!m.pole) return;
      picked.x.push(m.pole.frequency_hz);
      picked.y.push(m.pole.order);
      picked.text.push('mode ' + (k + 1) + ': ' + fmt(m.frequency_hz, 3) + ' Hz');
    });
    traces.push({ type: 'scatter', mode: 'markers', name: 'picked', x: picked.x, y: picked.y, text: picked.text,
      hoverinfo: 'text', marker: { symbol: 'circle-open', color: '#000', size: 15, line: { width: 2 } } });
    var mi = fixed.indicator;
    traces.push({ type: 'scatter', mode: 'lines', name: 'sum of |H|', x: mi.frequency_hz, y: mi.sum_frf, yaxis: 'y2',
      line: { color: '#888', width: 1 }, hoverinfo: 'skip' });
    (mi.cmif || []).forEach(function (sv, i) {
      traces.push({ type: 'scatter', mode: 'lines', name: 'CMIF ' + (i + 1), x: mi.cmif_frequency_hz, y: sv, yaxis: 'y2',
        line: { color: i === 0 ? '#762a83' : '#c2a5cf', width: 1 }, hoverinfo: 'skip' });
    });
    return traces;
  }
  function stabLayout() {
    var band = fixed.band_hz;
    var shapes = (state.modes || []).map(function (m) {
      return { type: 'line', x0: m.frequency_hz, x1: m.frequency_hz, yref: 'paper', y0: 0, y1: 1,
        line: { color: '#2166ac', dash: 'dash', width: 1 } };
    });
    return { height: 420, margin: { l: 55, r: 60, t: 10, b: 40 }, font: { size: 12 }, hovermode: 'closest',
      uirevision: 'keep', showlegend: true, legend: { orientation: 'h', y: -0.17, font: { size: 11 } },
      xaxis: { title: { text: 'frequency (Hz)' }, range: [band[0], band[1]] },
      yaxis: { title: { text: 'model order' }, range: [fixed.orders[0] - 1, fixed.orders[1] + 1] },
      yaxis2: { title: { text: 'sum |H|, CMIF' }, overlaying: 'y', side: 'right', type: 'log', showgrid: false, dtick: 1,
        exponentformat: 'power' },
      shapes: shapes };
  }
  function frfTraces() {
    var items = fixed.frfs.items, i = Number($('frf-select').value) || 0;
    if (!items.length) return [];
    var item = items[i], fit = (state.synthesised || [])[i] || { magnitude: [], phase_deg: [] };
    var f = fixed.frfs.frequency_hz;
    return [
      { type: 'scatter', mode: 'lines', name: 'measured |H|', x: f, y: item.magnitude, line: { color: '#2166ac' } },
      { type: 'scatter', mode: 'lines', name: 'synthesised |H|', x: f, y: fit.magnitude, line: { color: '#d6604d', dash: 'dash' } },
      { type: 'scatter', mode: 'lines', name: 'measured phase', x: f, y: item.phase_deg, yaxis: 'y2',
        line: { color: '#2166ac', width: 1 }, showlegend: false },
      { type: 'scatter', mode: 'lines', name: 'synthesised phase', x: f, y: fit.phase_deg, yaxis: 'y2',
        line: { color: '#d6604d', width: 1, dash: 'dash' }, showlegend: false }
    ];
  }
  function frfLayout() {
    var band = fixed.band_hz;
    return { height: 300, margin: { l: 60, r: 20, t: 36, b: 40 }, font: { size: 12 }, uirevision: 'keep',
      legend: { orientation: 'h', y: 1.02, yanchor: 'bottom', x: 0.5, xanchor: 'center', font: { size: 11 } },
      shapes: [band[0], band[1]].map(function (x) {
        return { type: 'line', x0: x, x1: x, yref: 'paper', y0: 0, y1: 1, line: { color: '#bbb', width: 1 } };
      }),
      xaxis: { title: { text: 'frequency (Hz)' }, anchor: 'y2' },
      yaxis: { title: { text: '|H| (' + fixed.frfs.unit + ')' }, type: 'log', domain: [0.34, 1] },
      yaxis2: { title: { text: 'phase (°)' }, domain: [0, 0.27], range: [-180, 180], dtick: 90 } };
  }
  function macTrace() {
    var labels = (state.modes || []).map(function (m, k) { return (k + 1) + ': ' + fmt(m.frequency_hz, 1); });
    return [{ type: 'heatmap', z: state.mac, x: labels, y: labels, zmin: 0, zmax: 1,
      colorscale: [[0, '#f7fbff'], [0.5, '#6baed6'], [1, '#08306b']], colorbar: { thickness: 12 },
      hovertemplate: '%{y} / %{x}<br>MAC %{z:.3f}<extra></extra>' }];
  }
  function macLayout() {
    var annotations = [];
    (state.mac || []).forEach(function (row, i) {
      row.forEach(function (v, j) {
        annotations.push({ x: j, y: i, xref: 'x', yref: 'y', text: Number(v).toFixed(2), showarrow: false,
          font: { size: 10, color: v > 0.6 ? 'white' : 'black' } });
      });
    });
    return { height: 320, margin: { l: 80, r: 10, t: 10, b: 70 }, font: { size: 11 }, annotations: annotations,
      xaxis: { type: 'category' }, yaxis: { type: 'category', autorange: 'reversed' } };
  }
  function drawTable() {
    var tbody = $('modes').tBodies[0];
    tbody.textContent = '';
    (state.modes || []).forEach(function (m, k) {
      var tr = document.createElement('tr');
      var cells = [k + 1, fmt(m.frequency_hz, 3) + sigma(m.frequency_std_hz),
        fmt(100 * m.damping_ratio, 3) + sigma(m.damping_ratio_std === null ? null : 100 * m.damping_ratio_std),
        fmt(m.mpc, 3), fmt(m.mpd_deg, 1), m.pole ? 'order ' + m.pole.order + ' ' + m.pole.label : ''];
      cells.forEach(function (c) {
        var td = document.createElement('td');
        td.textContent = String(c);
        tr.appendChild(td);
      });
      var td = document.createElement('td');
      td.className = 'remove';
      var b = document.createElement('button');
      b.textContent = '×';
      b.title = 'Remove this mode';
      b.addEventListener('click', function () { removeMode(k); });
      td.appendChild(b);
      tr.appendChild(td);
      tbody.appendChild(tr);
    });
    if (!(state.modes || []).length) {
      var tr = document.createElement('tr');
      var td = document.createElement('td');
      td.colSpan = 7;
      td.style.textAlign = 'left';
      td.textContent = 'No mode picked: click a pole in the diagram.';
      tr.appendChild(td);
      tbody.appendChild(tr);
    }
    $('refinement').textContent = (state.refinement || '').replace(/ -> /g, ' → ');
    var ul = $('warnings');
    ul.textContent = '';
    (state.warnings || []).forEach(function (w) {
      var li = document.createElement('li');
      li.textContent = w;
      ul.appendChild(li);
    });
    $('command').textContent = state.command;
    $('save').disabled = !state.can_save;
  }
  function draw() {
    drawTable();
    return Promise.all([
      Plotly.react($('stab'), stabTraces(), stabLayout(), plotConfig),
      Plotly.react($('frf'), frfTraces(), frfLayout(), plotConfig),
      Plotly.react($('mac'), macTrace(), macLayout(), plotConfig)
    ]).then(function () {
      api.redraws += 1;
      body.setAttribute('data-redraws', String(api.redraws));
    });
  }

  // ---- picking ----

  function describe(s) {
    var n = (s.modes || []).length;
    return s.selection === 'automatic' ? n + ' mode(s), automatic selection' :
      s.selection === 'none' ? 'nothing picked' : n + ' mode(s) picked by hand';
  }
  // Runs one pick after the previous ones (clicks made during a fit wait their turn).
  function enqueue(makeRequest, what) {
    var run = queue.then(function () {
      var t0 = performance.now();
      body.classList.add('busy');
      status(what + ' …');
      return request('POST', '/api/select', makeRequest()).then(function (s) {
        state = s;
        dirty = true;
        doneAsked = false;
        api.lastFetchMs = performance.now() - t0;
        return draw().then(function () {
          api.lastRedrawMs = performance.now() - t0;
          body.setAttribute('data-last-redraw-ms', String(Math.round(api.lastRedrawMs)));
          status(what + ': ' + describe(s) + ' (fit ' + Math.round(1000 * s.fit_seconds) + ' ms, redrawn in ' +
            Math.round(api.lastRedrawMs) + ' ms)' + (s.can_save ? '' : fixed.outputs.modes ? '' : ' — no -o given: Save is off'));
          return s;
        });
      }, function (e) {
        status(what + ': refused: ' + e.message, true);
        throw e;
      }).finally(function () { body.classList.remove('busy'); });
    });
    queue = run.catch(function () {});
    return run;
  }
  function currentPicked() { return (state.picked_hz || []).slice(); }
  // The picked mode whose pole column holds a pole at (f, zeta): as ema fit --select groups a
  // column, within 0.5 % in frequency and 25 % in damping of the mode's pole; -1 when none.
  function pickedModeAt(f, zeta) {
    var hit = -1, best = Infinity;
    (state.modes || []).forEach(function (m, k) {
      if (!m.pole) return;
      var df = Math.abs(m.pole.frequency_hz - f) / m.pole.frequency_hz;
      var sameDamping = zeta === undefined || zeta === null ||
        Math.abs(zeta - m.pole.damping_ratio) < 0.25 * m.pole.damping_ratio;
      if (df < 0.005 && sameDamping && df < best) { best = df; hit = k; }
    });
    return hit;
  }
  function requestedOf(m) { return m.requested_hz !== undefined ? m.requested_hz : m.pole.frequency_hz; }
  function withoutMode(k) {
    var gone = requestedOf(state.modes[k]);
    return currentPicked().filter(function (f) { return f !== gone; });
  }
  function removeMode(k) {
    var m = state.modes[k];
    return enqueue(function () { return { frequencies_hz: withoutMode(k) }; }, 'remove ' + fmt(m.frequency_hz, 2) + ' Hz');
  }
  api.toggle = function (f, zeta) {
    return enqueue(function () {
      var k = pickedModeAt(f, zeta);
      return { frequencies_hz: k >= 0 ? withoutMode(k) : currentPicked().concat([f]) };
    }, 'pole at ' + fmt(f, 2) + ' Hz');
  };
  api.select = function (list) {
    return enqueue(function () { return { frequencies_hz: list }; }, 'pick of ' + list.length + ' frequencies');
  };
  api.auto = function () { return enqueue(function () { return { selection: 'auto' }; }, 'automatic selection'); };
  api.state = function () { return state; };
  api.fixed = function () { return fixed; };
  api.polePoint = function (i) {
    var gd = $('stab'), full = gd._fullLayout, box = gd.getBoundingClientRect();
    return { x: box.left + full._size.l + full.xaxis.l2p(fixed.diagram.frequency_hz[i]),
             y: box.top + full._size.t + full.yaxis.l2p(fixed.diagram.order[i]) };
  };
  api.save = function () {
    var run = queue.then(function () {
      status('saving …');
      return request('POST', '/api/save', {}).then(function (r) {
        state = r.state;
        dirty = false;
        drawTable();
        status('saved ' + r.written.join(', ') + ' — the same files as: ' + r.command);
        return r;
      }, function (e) {
        status('save refused: ' + e.message, true);
        throw e;
      });
    });
    queue = run.catch(function () {});
    return run;
  };
  api.done = function () {
    return request('POST', '/api/done', {}).then(function (r) {
      status('ema pick has ended; this page no longer answers. You may close it.');
      Array.prototype.forEach.call(document.querySelectorAll('button'), function (b) { b.disabled = true; });
      body.setAttribute('data-ended', '1');
      return r;
    });
  };

  // ---- wiring ----

  function wire() {
    var select = $('frf-select');
    fixed.frfs.items.forEach(function (item, i) {
      var o = document.createElement('option');
      o.value = String(i);
      o.textContent = item.label + (item.driving ? ' (driving point)' : '');
      select.appendChild(o);
    });
    select.addEventListener('change', function () { Plotly.react($('frf'), frfTraces(), frfLayout(), plotConfig); });
    $('stab').on('plotly_click', function (ev) {
      var p = (ev.points || []).filter(function (q) { return q.data.meta === 'poles'; })[0];
      if (!p) return;
      var i = p.customdata;
      if (fixed.diagram.label[i] === 'x') {
        status('a non-physical pole (ζ ≤ 0 or outside the band) cannot be picked', true);
        return;
      }
      api.toggle(fixed.diagram.frequency_hz[i], fixed.diagram.damping_ratio[i]).catch(function () {});
    });
    $('auto').addEventListener('click', function () { api.auto().catch(function () {}); });
    $('clear').addEventListener('click', function () { api.select([]).catch(function () {}); });
    $('save').addEventListener('click', function () { api.save().catch(function () {}); });
    $('done').addEventListener('click', function () {
      if (dirty && state.can_save && !doneAsked) {
        doneAsked = true;
        status('the pick is not saved: click Done again to end without saving', true);
        return;
      }
      api.done().catch(function (e) { status('Done failed: ' + e.message, true); });
    });
    $('load').addEventListener('change', function (ev) {
      var file = ev.target.files[0];
      if (!file) return;
      file.text().then(function (text) {
        var modes = JSON.parse(text).modes;
        if (!Array.isArray(modes)) throw new Error('no "modes" array (expected ema fit --json)');
        var band = fixed.band_hz;
        var list = modes.map(function (m) { return m.frequency_hz; })
          .filter(function (f) { return typeof f === 'number' && f >= band[0] && f <= band[1]; });
        if (!list.length) throw new Error('no mode frequency inside the band');
        return api.select(list);
      }).catch(function (e) { status('Load ' + file.name + ': ' + e.message, true); });
      ev.target.value = '';
    });
  }

  request('GET', '/api/data').then(function (data) {
    fixed = data.fixed;
    state = data.state;
    var band = fixed.band_hz;
    $('subtitle').textContent = fixed.input + ' — band ' + fmt(band[0], 1) + '–' + fmt(band[1], 1) + ' Hz, orders ' +
      fixed.orders[0] + '..' + fixed.orders[1] + (fixed.outputs.modes ? ' — Save writes ' + fixed.outputs.modes +
      (fixed.outputs.json ? ' and ' + fixed.outputs.json : '') : ' — no -o: Save is off');
    return draw().then(function () {
      wire();
      dirty = false;
      status(describe(state) + '. Click a pole to pick or remove a mode.');
      api.ready = true;
      body.setAttribute('data-ready', '1');
    });
  }).catch(function (e) {
    status('cannot load the data: ' + e.message, true);
    noteError(e.message);
  });
})();
