// The ema report page: draws every chart from the JSON embedded in <script id="ema-data"> with
// plotly.js (embedded above). When every chart has rendered, <body> gets data-charts-rendered equal
// to data-charts-expected (the headless-browser test checks this); errors land in data-errors.
(function () {
  'use strict';
  var body = document.body;
  var errors = [];
  function noteError(message) {
    errors.push(String(message));
    body.setAttribute('data-errors', errors.join(' | '));
  }
  window.addEventListener('error', function (e) { noteError(e.message || e); });
  window.addEventListener('unhandledrejection', function (e) { noteError(e.reason || 'promise rejected'); });

  var data = JSON.parse(document.getElementById('ema-data').textContent);
  var main = document.getElementById('report');
  var expected = 0;
  var rendered = 0;
  var pending = [];
  var config = { responsive: true, displaylogo: false };

  function el(tag, attrs, children) {
    var node = document.createElement(tag);
    if (attrs) Object.keys(attrs).forEach(function (k) {
      if (k === 'text') node.textContent = attrs[k]; else node.setAttribute(k, attrs[k]);
    });
    (children || []).forEach(function (c) { node.appendChild(typeof c === 'string' ? document.createTextNode(c) : c); });
    return node;
  }
  function section(parent, title, note) {
    var s = el('section', { 'class': 'card' }, [el('h2', { text: title })]);
    if (note) s.appendChild(el('p', { 'class': 'note', text: note }));
    parent.appendChild(s);
    return s;
  }
  function unavailable(parent, what) {
    parent.appendChild(el('p', { 'class': 'missing', text: what + ': not available in this run.' }));
  }
  // Every chart downloads as PNG and as SVG with its title (the section's heading) drawn in: the
  // modebar's two camera buttons replace plotly's single PNG one. exportChart is also what the
  // page's self-check (#export-check, used by the headless-browser test) runs.
  var charts = [];
  function fileName(title) { return title.replace(/[^A-Za-z0-9._-]+/g, '_').replace(/^_+|_+$/g, '') || 'chart'; }
  function exportChart(gd, format, title) {
    var layout = Object.assign({}, gd.layout, {
      title: { text: title, x: 0.01, xanchor: 'left', font: { size: 15 } },
      margin: Object.assign({}, gd.layout.margin || {}, { t: 60 }) });
    var size = gd.getBoundingClientRect();
    return Plotly.toImage({ data: gd.data, layout: layout }, { format: format,
      width: Math.max(600, Math.round(size.width) || 900), height: Math.max(300, Math.round(size.height) || 460) });
  }
  function chartTitle(div) {
    var sec = div.closest ? div.closest('section') : null;
    var heading = sec ? sec.querySelector('h2') : null;
    return heading ? heading.textContent : document.title;
  }
  function downloadButton(format) {
    return { name: 'download-' + format, title: 'Download ' + format.toUpperCase() + ' (with title)',
      icon: Plotly.Icons.camera, click: function (gd) {
        var title = chartTitle(gd);
        exportChart(gd, format, title).then(function (url) {
          var a = el('a', { href: url, download: fileName(title) + '.' + format });
          document.body.appendChild(a);
          a.click();
          a.remove();
        }, function (e) { noteError(e); });
      } };
  }
  function chart(parent, traces, layout, cls) {
    var div = el('div', { 'class': 'chart ' + (cls || '') });
    parent.appendChild(div);
    expected += 1;
    layout = Object.assign({ margin: { l: 60, r: 60, t: 30, b: 50 }, font: { size: 12 },
      legend: { orientation: 'h', y: -0.2 } }, layout);
    charts.push(div);
    var cfg = Object.assign({}, config, { modeBarButtonsToRemove: ['toImage'],
      modeBarButtonsToAdd: [downloadButton('png'), downloadButton('svg')] });
    pending.push(Plotly.newPlot(div, traces, layout, cfg).then(function () {
      rendered += 1;
      div.setAttribute('data-rendered', '1');
      return div;
    }));
    return div;
  }
  function fmt(v, digits) {
    return (v === null || v === undefined || isNaN(v)) ? '–' : Number(v).toFixed(digits);
  }
  // A table with its header row in <thead> (repeated on every printed page a long table spans).
  function table(parent, headers, rows, cls) {
    var t = el('table', { 'class': cls || '' });
    t.appendChild(el('thead', null, [el('tr', null, headers.map(function (h) { return el('th', { text: h }); }))]));
    var tb = el('tbody');
    rows.forEach(function (r) {
      tb.appendChild(el('tr', null, r.map(function (c) { return el('td', { text: String(c) }); })));
    });
    t.appendChild(tb);
    parent.appendChild(t);
    return t;
  }

  // ---- the first screen: the run's headline and what the diagnosis found (data.diagnosis_view,
  // app/report/report_data.cpp DiagnosisView: read from DIAG.json, folded and put into words) ----
  var view = data.diagnosis_view || {};
  var story = view.story;
  var diag = data.diagnosis || {};
  function pct(p) { return (p === null || p === undefined || isNaN(p)) ? '–' : (100 * p).toFixed(1) + ' %'; }
  function num(v) {  // an error in % or a MAC: enough digits for 0.064 % as for 114 %
    if (v === null || v === undefined || isNaN(v)) return '–';
    var a = Math.abs(v);
    return a >= 100 ? v.toFixed(0) : a >= 10 ? v.toFixed(1) : a >= 1 ? v.toFixed(2) : Number(v.toPrecision(2)).toString();
  }
  function sigmas(v) {  // a misfit in σ, signed
    if (v === null || v === undefined || isNaN(v)) return '–';
    var a = Math.abs(v);
    var s = a >= 100 ? a.toFixed(0) : a >= 10 ? a.toFixed(1) : a.toFixed(2);
    return s === '0.00' ? s : (v < 0 ? '−' : '+') + s;
  }
  function kindWords(kind) { return String(kind || '').replace(/_/g, ' ').replace(/\+/g, ' + '); }
  // A target such as "bearings+points:110" may wrap after '+', '/' and ':' (zero-width spaces).
  function breakable(target) { return String(target || '').replace(/([+\/:])/g, '$1\u200b'); }
  function sci(v) {  // a reduced χ²: 0.83, 14.2, 1.1e5, 2.2e-5
    if (v === null || v === undefined || isNaN(v)) return '–';
    if (v === 0 || (Math.abs(v) >= 0.01 && Math.abs(v) < 1e4)) return Number(v.toPrecision(3)).toString();
    var e = Math.floor(Math.log10(Math.abs(v)));
    return (v / Math.pow(10, e)).toFixed(1) + 'e' + e;
  }
  var hasDiagnosis = !!(story && diag.candidates && diag.candidates.length);
  if (hasDiagnosis || (data.setups || []).length) {
    var fs0 = el('section', { 'class': 'card first-screen', id: 'first-screen' });
    main.appendChild(fs0);
    if ((data.setups || []).length) {
      var agreeMac = function (c) {
        var s = (c || {}).summary;
        return s ? fmt(s.mean_agreement_pct, 1) + ' % / ' + fmt(s.mean_mac, 3) : '–';
      };
      table(fs0, ['test', 'FRFs', 'impacts rejected', 'modes', 'model as given: agreement / MAC',
        'updated model: agreement / MAC'], data.setups.map(function (s) {
        return [s.name, s.frf_count === undefined ? '–' : s.frf_count, (s.rejected || []).length,
          s.mode_count === undefined ? '–' : s.mode_count, agreeMac(s.correlation_before), agreeMac(s.correlation_after)];
      }), 'headline');
      if (data.agreement_note) fs0.appendChild(el('p', { 'class': 'agreement-note', text: data.agreement_note }));
      data.setups.forEach(function (s) {  // a simulated test must never read as a measurement
        if (s.rehearsal) fs0.appendChild(el('p', { 'class': 'rehearsal', text: s.name + ': ' + s.rehearsal }));
      });
    }
    if (hasDiagnosis) {
      var st = el('div', { 'class': 'story', id: 'diagnosis-story' });
      fs0.appendChild(st);
      var n = story.effects.length;
      // No effect, and the model still inadequate with its own error dominating: something is
      // missing that the vocabulary cannot say — never "nothing is missing".
      var outside = !n && story.noise_consistent === false && story.model_error_note;
      st.appendChild(el('h2', { text: n ? 'Diagnosis: the model misses ' + n + ' effect' + (n > 1 ? 's' : '') :
        outside ? 'Diagnosis: no effect the model can try explains the mismatch beyond its own error' :
        'Diagnosis: no missing effect found' }));
      st.appendChild(el('p', { 'class': 'lead', text: n ?
        'Rank 1 of ' + view.candidate_count + ' candidates (probability ' + pct(story.probability) + ' for this exact ' +
        'reading). Each effect below with its probability summed over every candidate that holds it, and its fitted value ± 1σ:' :
        story.model_error_lookalike ||
        'No candidate explains the mismatch by more than its prior and parameter cost (probability ' + pct(story.probability) + ').' }));
      if (n) {
        st.appendChild(el('ol', { 'class': 'effects' }, story.effects.map(function (e) {
          var head = el('div', { 'class': 'effect-head' }, [el('span', { 'class': 'effect-name', text: e.description }),
            el('span', { 'class': 'prob' + (e.probability >= 0.9 ? ' sure' : e.probability < 0.5 ? ' unsure' : ''),
              text: pct(e.probability) })]);
          if (e.any && e.any.probability !== null) head.appendChild(el('span', { 'class': 'prob any',
            text: pct(e.any.probability) + ' on any of ' + e.any.target }));
          var item = el('li', null, [head]);
          if (e.values) item.appendChild(el('div', { 'class': 'effect-values', text: e.values }));
          return item;
        })));
      }
      st.appendChild(el('p', { 'class': 'errline', text: 'Mean frequency error ' + num(story.error_before_pct) + ' % → ' +
        num(story.error_after_pct) + ' %, mean MAC ' + fmt(story.mac_before, 3) + ' → ' + fmt(story.mac_after, 3) +
        ' (the model as given → with rank 1).' }));
      var adequacy = el('div', { 'class': 'adequacy ' + (story.noise_consistent === true ? 'ok' :
        story.noise_consistent === false ? 'bad' : 'unknown'), id: 'adequacy' },
        [el('strong', { text: story.adequacy_headline || '' }),
          story.adequacy_detail ? ' — ' + story.adequacy_detail : '']);
      if (story.noise_consistent === false && story.failing_modes && story.failing_modes.length) {
        adequacy.appendChild(el('div', { 'class': 'failing', text: 'Where: ' + story.failing_modes.slice(0, 4).join('; ') +
          (story.failing_modes.length > 4 ? '; and ' + (story.failing_modes.length - 4) + ' more' : '') +
          ' (evidence per test mode below).' }));
      }
      if (story.model_error_note) adequacy.appendChild(el('div', { 'class': 'model-error', text: story.model_error_note }));
      st.appendChild(adequacy);
      if (n) {
        var alike = story.lookalikes || [];
        st.appendChild(el('p', { 'class': 'lookalikes' }, [el('strong', { text: 'Look-alikes these data cannot separate: ' }),
          alike.length ? alike.map(function (a) { return a.text + ' ' + pct(a.probability); }).join('; ') + '.' :
            'none within a factor 20 of rank 1.']));
      }
      if (story.checks && story.checks.length) {
        st.appendChild(el('ul', { 'class': 'checks' }, story.checks.map(function (c) {
          return el('li', null, [el('strong', { text: 'Check: ' }), String(c) + '.']);
        })));
      }
    }
    if (data.problems && data.problems.length) {
      fs0.appendChild(el('p', { 'class': 'missing', text: 'Steps that did not complete:' }));
      fs0.appendChild(el('ul', null, data.problems.map(function (p) { return el('li', { text: p }); })));
    }
  }

  // ---- the diagnosis: evidence per test mode, the candidates with look-alikes folded, the charts ----
  var dg = section(main, 'Which physical effect is missing? The evidence and every candidate',
    'Every effect of the vocabulary, on every group, member, point and body, and combinations of up to three, ' +
    'fitted to all tests at once and ranked by posterior probability (rank 1 = most likely missing effects).');
  dg.id = 'diagnosis';
  if (hasDiagnosis) {
    var cands = diag.candidates.slice().sort(function (a, b) { return a.rank - b.rank; });
    if (diag.explanation) dg.appendChild(el('p', { 'class': 'explanation', text: String(diag.explanation) }));

    // Evidence per test mode.
    var modes = view.modes || [];
    dg.appendChild(el('h3', { text: 'Evidence per test mode: which modes drove the answer, where the model still fails' }));
    if (modes.length) {
      dg.appendChild(el('p', { 'class': 'note', text: 'Misfit = (model − test) / σ of the test frequency (shape: (1 − MAC) / ' +
        'shape σ); within ±2σ the model matches to the measurement\'s noise. "As given" is the nominal model, "rank 1" the ' +
        'model with rank 1\'s effects. Share: the mode\'s part of the fall in χ² from the model as given to rank 1 (the ' +
        'modes that drove the answer). Unpaired: no model mode pairs with the test mode.' }));
      var ev = table(dg, ['test', 'mode', 'f test ± σ (Hz)', 'model f (Hz) as given → rank 1', 'frequency misfit (σ)',
        'MAC', 'shape misfit (σ)', 'share of the fall', 'with rank 1'], [], 'evidence');
      ev.id = 'evidence';
      var tb = ev.querySelector('tbody');
      // Two tests of one setup (a repeat, a follow-up test): their modes told apart by the test.
      var severalTests = modes.some(function (a) {
        return modes.some(function (b) { return a.setup === b.setup && a.test !== undefined && a.test !== b.test; });
      });
      modes.forEach(function (m) {
        var tr = el('tr', { 'class': 'v-' + m.verdict.replace(/ /g, '-') });
        var cell = function (text, cls) { var td = el('td', { text: text }); if (cls) td.className = cls; tr.appendChild(td); return td; };
        // "as given → rank 1"; a line may break after the arrow only.
        var arrow = function (b, a, f, pb, pa) {
          return !pb && !pa ? 'unpaired' : (pb ? f(b) : 'unpaired') + '\u00a0→ ' + (pa ? f(a) : 'unpaired');
        };
        cell((m.setup || '') + (severalTests ? (m.setup ? ', ' : '') + 'test ' + m.test : ''));
        cell(String(m.test_mode));
        cell(fmt(m.test_frequency_hz, 2) + '\u00a0± ' + (m.sigma_hz === null ? '–' : Number(m.sigma_hz).toPrecision(2)));
        cell(arrow(m.model_frequency_hz_before, m.model_frequency_hz_after, function (v) { return fmt(v, 1); },
          m.paired_before, m.paired_after));
        cell(arrow(m.frequency_misfit_sigma_before, m.frequency_misfit_sigma_after, sigmas, m.paired_before, m.paired_after), 'after');
        cell(arrow(m.mac_before, m.mac_after, function (v) { return fmt(v, 3); }, m.paired_before, m.paired_after));
        cell(arrow(m.shape_misfit_sigma_before, m.shape_misfit_sigma_after, function (v) { return fmt(v, 2); },
          m.paired_before, m.paired_after));
        var share = cell('', 'share');
        if (m.share_pct !== null && m.share_pct !== undefined) {
          share.appendChild(el('span', { 'class': 'bar', style: 'width:' + Math.max(1, Math.round(0.4 * m.share_pct)) + 'px' }));
          share.appendChild(document.createTextNode(' ' + m.share_pct.toFixed(m.share_pct < 10 ? 1 : 0) + ' %'));
        } else share.textContent = '–';
        cell(m.verdict, 'verdict-cell');
        tb.appendChild(tr);
      });
    } else {
      unavailable(dg, 'Evidence per test mode (DIAG.json "modes")');
    }

    // The candidates, one row per group of look-alikes; a group's members open under it.
    var groups = view.groups || [];
    dg.appendChild(el('h3', { text: 'Candidates: ' + groups.length + ' readings of ' + cands.length +
      ' candidates (the same reading on other members or points folded into one row)' }));
    var ct = table(dg, ['rank', 'effect(s)', 'where', 'fitted values of the best (± 1σ)', 'probability (summed)',
      'mean |f error| %', 'mean MAC', 'reduced χ²'], [], 'small candidates');
    ct.id = 'candidates';
    var ctb = ct.querySelector('tbody');
    var candidateRow = function (c, member) {
      var tr = el('tr', { 'class': member ? 'member' : 'group' + (c.rank === 1 ? ' rank1' : '') });
      var td = function (content, cls) {
        var cellEl = el('td', cls ? { 'class': cls } : null, Array.isArray(content) ? content : [String(content)]);
        tr.appendChild(cellEl);
        return cellEl;
      };
      td(String(c.rank));
      td(member ? '' : kindWords(c.kind), 'text');
      var where = td([breakable(c.target) || '—'], 'text');
      td([c.parameters || ''].concat((c.flags || []).map(function (f) { return el('div', { 'class': 'flag', text: 'Check: ' + f }); })), 'text');
      td(pct(c.probability));
      td(num(c.mean_abs_frequency_error_pct));
      td(fmt(c.mean_mac, 3));
      td(sci(c.reduced_chi2));
      ctb.appendChild(tr);
      return where;
    };
    groups.forEach(function (g) {
      var where = candidateRow(g, false);
      if (!g.more) return;
      var memberRows = [];
      var button = el('button', { type: 'button', 'class': 'more', 'aria-expanded': 'false',
        text: '+ ' + g.more + ' more ' + g.more_noun + (g.pattern && g.pattern !== g.target ? ' (' + breakable(g.pattern) + ')' : '') });
      where.appendChild(el('br'));
      where.appendChild(button);
      g.members.forEach(function (m) {
        candidateRow(m, true);
        memberRows.push(ctb.lastChild);
      });
      button.addEventListener('click', function () {
        var open = button.getAttribute('aria-expanded') !== 'true';
        button.setAttribute('aria-expanded', open ? 'true' : 'false');
        memberRows.forEach(function (r) { r.classList.toggle('open', open); });
      });
    });

    // Charts: the ranking (one bar per reading) and the error per mode before and after.
    var shownGroups = groups.slice(0, 12);
    var baseErr = diag.baseline ? diag.baseline.mean_abs_frequency_error_pct : null;
    var label = function (g) {
      return '#' + g.rank + ' ' + kindWords(g.kind) + (g.target ? ' (' + g.target + (g.more ? ' +' + g.more : '') + ')' : '');
    };
    var labels = shownGroups.map(label).reverse();
    var errs = shownGroups.map(function (g) { return g.mean_abs_frequency_error_pct; }).reverse();
    var bars = [{ type: 'bar', orientation: 'h', name: 'mean |frequency error| after fitting (%)', y: labels, x: errs,
      marker: { color: shownGroups.map(function (g) { return g.rank === 1 ? '#1b7837' : '#92c5de'; }).reverse() },
      text: errs.map(function (e) { return num(e) + ' %'; }), textposition: 'outside', cliponaxis: false,
      hovertext: shownGroups.map(function (g) { return 'probability ' + pct(g.probability); }).reverse() }];
    var dshapes = [];
    if (baseErr !== null && baseErr !== undefined) {
      dshapes.push({ type: 'line', x0: baseErr, x1: baseErr, yref: 'paper', y0: 0, y1: 1, line: { color: '#b2182b', dash: 'dash' } });
    }
    var row = el('div', { 'class': 'row' });
    dg.appendChild(row);
    var c1 = el('div', { 'class': 'col' }, [el('h3', { text: 'Ranking, one bar per reading (dashed: the model as given)' })]);
    var c2 = el('div', { 'class': 'col' }, [el('h3', { text: 'The error falls, per test mode' })]);
    row.appendChild(c1);
    row.appendChild(c2);
    chart(c1, bars, { height: Math.max(300, 34 * shownGroups.length + 100), xaxis: { title: { text: 'mean |frequency error| (%)' }, type: 'log' },
      margin: { l: 20, r: 60, t: 10, b: 50 }, yaxis: { automargin: true }, shapes: dshapes, showlegend: false }, 'half');
    var fallX = [], fallSetup = [], fallMode = [], before = [], after = [];
    (data.setups || []).forEach(function (setup) {
      var b = (setup.correlation_before || {}).pairs || [];
      var a = (setup.correlation_after || {}).pairs || [];
      b.forEach(function (p) {
        var q = a.filter(function (x) { return x.test_mode === p.test_mode; })[0];
        fallX.push(setup.name + ' T' + p.test_mode);
        fallSetup.push(setup.name);
        fallMode.push('T' + p.test_mode);
        before.push(100 - p.agreement_pct);
        after.push(q ? 100 - q.agreement_pct : null);
      });
    });
    var fall;
    if (fallX.length) {
      // Two-level axis: the test mode under its setup (no slanted labels to collide).
      fall = [{ type: 'bar', name: 'model as given', x: [fallSetup, fallMode], y: before, marker: { color: '#d6604d' } },
        { type: 'bar', name: 'updated model (rank 1)', x: [fallSetup, fallMode], y: after, marker: { color: '#1b7837' } }];
    } else {
      fall = [{ type: 'bar', x: ['model as given', 'rank 1'],
        y: [baseErr, cands[0].mean_abs_frequency_error_pct], marker: { color: ['#d6604d', '#1b7837'] } }];
    }
    chart(c2, fall, { height: 360, barmode: 'group', yaxis: { title: { text: '100 − agreement (%)' }, type: 'log', dtick: 1 },
      xaxis: { automargin: true }, legend: { orientation: 'h', y: -0.25 } }, 'half');
  } else {
    unavailable(dg, 'Diagnosis');
  }

  // ---- the diagnosis' story: where it acts, the error falling effect by effect and over versions ----
  // (issue 13; kept in this block so other report sections stay untouched)
  (function drawDiagnosisStory() {
    var story = section(main, 'Where, effect by effect, version by version',
      'Rank 1\'s members and points on the test geometry; the error as each of its effects is added; ' +
      'the model\'s agreement over the runs into this output folder (history.json).');
    story.id = 'where';
    var places = data.diagnosed_places || [];
    var geo = null;
    (data.setups || []).forEach(function (s) { if (!geo && s.shapes && s.shapes.nodes && s.shapes.nodes.length) geo = s.shapes; });
    var placed = places.filter(function (p) { return p.points && p.points.length; });
    // The test geometry (points and wireframe) under a figure's own markers.
    var geometryTraces = function () {
      var traces = [];
      if (!geo) return traces;
      traces.push({ type: 'scatter3d', mode: 'markers', name: 'test points', x: geo.nodes.map(function (n) { return n.x; }),
        y: geo.nodes.map(function (n) { return n.y; }), z: geo.nodes.map(function (n) { return n.z; }),
        text: geo.nodes.map(function (n) { return 'node ' + n.id; }), hoverinfo: 'text', marker: { size: 3, color: '#777' } });
      var lx = [], ly = [], lz = [];
      (geo.lines || []).forEach(function (l) {
        var a = geo.nodes[l[0]], b = geo.nodes[l[1]];
        lx.push(a.x, b.x, null); ly.push(a.y, b.y, null); lz.push(a.z, b.z, null);
      });
      if (lx.length) traces.push({ type: 'scatter3d', mode: 'lines', name: 'wireframe', x: lx, y: ly, z: lz,
        hoverinfo: 'skip', line: { color: '#bbb' } });
      return traces;
    };
    if (placed.length) {
      var traces = geometryTraces();
      var colours = ['#b2182b', '#2166ac', '#1b7837'];
      placed.forEach(function (p, i) {
        traces.push({ type: 'scatter3d', mode: 'markers+text', name: p.kind + ' on ' + p.target,
          x: p.points.map(function (q) { return q[0]; }), y: p.points.map(function (q) { return q[1]; }),
          z: p.points.map(function (q) { return q[2]; }), text: p.points.map(function () { return p.label; }),
          textposition: 'top center', marker: { size: 7, symbol: 'diamond', color: colours[i % colours.length] } });
      });
      story.appendChild(el('h3', { text: 'Diagnosed: ' + placed.map(function (p) { return p.target; }).join(' + ') }));
      chart(story, traces, { height: 420, margin: { l: 0, r: 0, t: 10, b: 0 }, scene: { aspectmode: 'data' } }, 'half');
    } else {
      story.appendChild(el('p', { text: 'Rank 1 is "none" or acts on no located place: nothing to highlight.' }));
    }
    // The next test: where one more roving set and the hammer would tell rank 1's look-alikes apart
    // (pipeline::NextTest, as `ema plan --candidates --keep` plans it).
    var next = data.next_test;
    if (next && next.error) {
      story.appendChild(el('p', { 'class': 'note', text: 'The test that would tell rank 1\'s look-alikes apart could not be ' +
        'planned: ' + next.error }));
    } else if (next && next.sets) {
      var sigma = function (v) { return v === null || v === undefined ? '–' : fmt(v, 1) + ' σ'; };
      story.appendChild(el('h3', { text: 'The next test: where the sensors tell the look-alikes apart' }));
      story.appendChild(el('p', { text: 'These data cannot separate ' + next.readings.join('; ') + '. One more roving set beside ' +
        next.test + '\'s ' + next.kept_sets + ' (ema plan --candidates DIAG.json --keep) would: the predicted test results of ' +
        'each pair of readings apart in units of the test\'s noise, now and with the new set.' }));
      var pos = {};
      if (geo) geo.nodes.forEach(function (n) { pos[n.id] = n; });
      var marks = function (dofs, name, symbol, colour, size) {
        var at = dofs.filter(function (d) { return pos[d.node]; });
        return { type: 'scatter3d', mode: 'markers+text', name: name, x: at.map(function (d) { return pos[d.node].x; }),
          y: at.map(function (d) { return pos[d.node].y; }), z: at.map(function (d) { return pos[d.node].z; }),
          text: at.map(function (d) { return d.node + d.dir; }), textposition: 'top center',
          marker: { size: size, symbol: symbol, color: colour } };
      };
      var kept = [], added = [];
      next.sets.forEach(function (set, i) {
        set.forEach(function (d) { (i < next.kept_sets ? kept : added).push(d); });
      });
      var nextTraces = geometryTraces();
      nextTraces.push(marks(kept, 'sensors of the test', 'circle', '#999', 4));
      nextTraces.push(marks(added, 'the new roving set', 'diamond', '#1b7837', 7));
      nextTraces.push(marks(next.references || [], 'hammer', 'x', '#d95f02', 7));
      if (geo) chart(story, nextTraces, { height: 420, margin: { l: 0, r: 0, t: 10, b: 0 }, scene: { aspectmode: 'data' } }, 'half');
      story.appendChild(el('p', { text: 'New set: ' + added.map(function (d) { return d.node + d.dir; }).join(', ') +
        '; hammer at ' + (next.references || []).map(function (d) { return d.node + d.dir; }).join(', ') + '.' }));
      table(story, ['reading', 'against', 'apart with the test', 'with the new set'], (next.separations || []).map(function (p) {
        return [p.a, p.b, sigma(p.sigma_before), sigma(p.sigma_after)];
      }));
    }
    // A log axis over whole decades around the values (a flat series gets one decade each side).
    var decades = function (values) {
      var logs = values.filter(function (v) { return v > 0; }).map(Math.log10);
      if (!logs.length) return undefined;
      return [Math.floor(Math.min.apply(null, logs)) - (Math.max.apply(null, logs) - Math.min.apply(null, logs) < 0.5 ? 1 : 0),
        Math.ceil(Math.max.apply(null, logs)) + (Math.max.apply(null, logs) - Math.min.apply(null, logs) < 0.5 ? 1 : 0)];
    };
    var steps = (data.diagnosis || {}).steps || [];
    if (steps.length > 1) {
      var sx = steps.map(function (st, i) { return i === 0 ? 'model as given' : '+ ' + st.added; });
      chart(story, [{ type: 'scatter', mode: 'lines+markers', name: 'mean |frequency error| (%)', x: sx,
        y: steps.map(function (st) { return st.mean_abs_frequency_error_pct; }) },
      { type: 'scatter', mode: 'lines+markers', name: '1 − mean MAC', x: sx, yaxis: 'y2',
        // 1 − MAC below 10⁻⁶ is rounding (MAC 1.000): drawn at 10⁻⁶, not as a log axis of noise.
        y: steps.map(function (st) { return Math.max(1 - st.mean_mac, 1e-6); }) }],
      { height: 320, yaxis: { title: { text: 'mean |frequency error| (%)' }, type: 'log', exponentformat: 'power' },
        yaxis2: { title: { text: '1 − mean MAC' }, overlaying: 'y', side: 'right', type: 'log', exponentformat: 'power',
          range: decades(steps.map(function (st) { return Math.max(1 - st.mean_mac, 1e-6); })), dtick: 1, showgrid: false },
        xaxis: { automargin: true }, legend: { orientation: 'h' } }, 'half');
    }
    var history = data.history || [];
    if (history.length) {
      var hx = history.map(function (h) { return 'v' + h.version + ' ' + String(h.hash || '').slice(0, 8); });
      var err = function (key) { return history.map(function (h) { return h[key] === null || h[key] === undefined ? null : 100 - h[key]; }); };
      chart(story, [{ type: 'scatter', mode: 'lines+markers', name: 'model as run (100 − mean agreement, %)', x: hx,
        y: err('mean_agreement_pct_before'),
        text: history.map(function (h) { return (h.effects || []).join('; ') || 'no [[effect]] blocks'; }) },
      { type: 'scatter', mode: 'lines+markers', name: 'with the diagnosed effect(s)', x: hx, y: err('mean_agreement_pct_after'),
        text: history.map(function (h) { return h.diagnosis ? h.diagnosis.kind + ' on ' + h.diagnosis.target : ''; }) }],
      { height: 320, yaxis: { title: { text: '100 − mean agreement (%)' }, type: 'log', dtick: 1,
        range: decades(err('mean_agreement_pct_before').concat(err('mean_agreement_pct_after'))) },
        xaxis: { title: { text: 'model version' } },
        legend: { orientation: 'h' } }, 'half');
      table(story, ['version', 'when', 'hash', 'effects in the model', 'mean agreement', 'diagnosed next'],
        history.map(function (h) {
          return [h.version, h.stamp || '', String(h.hash || '').slice(0, 12), (h.effects || []).join('; '),
            fmt(h.mean_agreement_pct_before, 2) + ' %',
            h.diagnosis ? h.diagnosis.kind + ' on ' + h.diagnosis.target + ' (p ' + fmt(100 * (h.diagnosis.probability || 0), 1) + ' %)' : ''];
        }), 'small');
    }
  })();

  // ---- per setup ----
  (data.setups || []).forEach(function (setup) {
    var wrap = el('div', { 'class': 'setup' }, [el('h2', { 'class': 'setup-title', text: 'Test ' + setup.name })]);
    main.appendChild(wrap);
    var frf = setup.frf || {};
    var band = setup.band_hz || [0, 0];

    // Data quality: coherence map, reciprocity, driving points, scatter, mode complexity.
    var q = setup.quality || {};
    var qs = section(wrap, 'Data quality — ' + setup.name,
      'Checks of the measured FRFs before fitting (ema quality, docs/quality.md): reciprocity H_ij against H_ji, the ' +
      'sign of each driving point at its resonances (a flip means an inverted sensor or hammer), the coherence of ' +
      'every FRF at every line (dark = low), the impact-to-impact scatter of |H| from coherence and the averaged ' +
      'impacts, and the complexity of each fitted mode (MPC, MPD, MCF).');
    if (q.verdict) qs.appendChild(el('p', { 'class': q.verdict === 'pass' ? 'verdict' : 'missing',
      text: 'Overall: ' + q.verdict + ' (' + q.warnings + ' warning(s) over ' + q.frf_count + ' FRFs)' }));
    if (q.coherence_map) {
      var cm = q.coherence_map;
      chart(qs, [{ type: 'heatmap', x: cm.frequency_hz, y: cm.labels, z: cm.z, zmin: 0, zmax: 1, colorscale: 'Viridis',
        colorbar: { title: { text: 'coherence' } },
        hovertemplate: '%{y}<br>%{x} Hz<br>coherence %{z}<extra></extra>' }],
        { height: Math.min(900, Math.max(260, 16 * cm.labels.length + 110)),
          xaxis: { title: { text: 'frequency (Hz)' } }, yaxis: { automargin: true, type: 'category' } });
    } else if (q.verdict) {
      unavailable(qs, 'Coherence map (the FRF file has no coherence)');
    }
    if (q.reciprocity && q.reciprocity.length) {
      qs.appendChild(el('h3', { text: 'Reciprocity' }));
      table(qs, ['H_ij / H_ji', 'difference %', 'verdict', 'reason'], q.reciprocity.map(function (c) {
        return [c.i.node + c.i.dir + ' / ' + c.j.node + c.j.dir, fmt(100 * c.relative_difference, 1), c.verdict, c.reason];
      }), 'small');
    }
    if (q.driving_points && q.driving_points.length) {
      qs.appendChild(el('h3', { text: 'Driving points' }));
      table(qs, ['DOF', 'resonances', 'wrong sign', 'verdict', 'reason'], q.driving_points.map(function (c) {
        return [c.dof.node + c.dof.dir, c.resonances, c.flipped, c.verdict, c.reason];
      }), 'small');
    }
    if (q.frfs_warn && q.frfs_warn.length) {
      qs.appendChild(el('h3', { text: 'Coherence and scatter warnings' }));
      table(qs, ['FRF', 'mean coherence', 'scatter % (median)', 'reason'], q.frfs_warn.map(function (c) {
        return [c.response.node + c.response.dir + ' / ' + c.reference.node + c.reference.dir, fmt(c.mean_coherence, 3),
          fmt(100 * c.median_random_error, 1), c.reason];
      }), 'small');
    }
    if (q.modes && q.modes.length) {
      qs.appendChild(el('h3', { text: 'Mode complexity' }));
      table(qs, ['mode', 'f (Hz)', 'MPC', 'MPD (deg)', 'MCF'], q.modes.map(function (m) {
        return [m.mode, fmt(m.frequency_hz, 2), fmt(m.mpc, 3), fmt(m.mpd_deg, 1), fmt(m.mcf, 3)];
      }), 'small');
    }
    if (q.notes && q.notes.length) qs.appendChild(el('ul', { 'class': 'note' }, q.notes.map(function (n) { return el('li', { text: n }); })));
    if (!q.verdict && !(q.modes && q.modes.length)) unavailable(qs, 'Data-quality checks');

    // Stabilisation diagram with the sum of FRFs on a second axis.
    var stab = section(wrap, 'Stabilisation diagram — ' + setup.name,
      'Poles of every model order (filled: stable in frequency, damping and participation vector; diamonds: stable ' +
      'in frequency and one more criterion or frequency only; open circles: new or unstable; ×: non-physical). ' +
      'Dashed lines: the modes selected (as the line below says). Grey: sum of all FRF magnitudes; purple: the first two ' +
      'singular values of the FRF matrix (CMIF: a peak in the second one is a close or repeated mode the sum hides); ' +
      'orange dots: the MMIF (0 to 1, dips at resonances). Drag to zoom, double-click to reset.');
    // Which selection the fit used: the automatic rule, the project's frequencies, or a pick made
    // by hand in ema pick during the run; the equivalent ema fit line repeats it in a script.
    var sel = setup.selection;
    if (sel && sel.select) {
      var how = sel.by_hand ? 'picked by hand in ema pick during this run' :
        sel.select === 'auto' ? 'automatic' : 'the frequencies the project gives';
      var p = el('p', { 'class': 'selection', 'data-by-hand': sel.by_hand ? '1' : '0' },
        ['Selection used: ' + how + (sel.rule ? ' (' + sel.rule + ')' : '') + '; modes: ']);
      p.appendChild(el('a', { href: sel.modes_json, text: sel.modes_json }));
      if (sel.by_hand) p.appendChild(document.createTextNode('. To repeat it without the browser: select = "' + sel.select +
        '" in this test\'s [[test]].'));
      stab.appendChild(p);
      if (sel.command) stab.appendChild(el('pre', { 'class': 'command', text: sel.command }));
    }
    var st = setup.stabilisation || {};
    if (st.order && st.order.length) {
      var groups = {};
      st.status.forEach(function (s, i) {
        var key = s === 'stable' ? 'stable' : s === 'non-physical' ? 'non-physical' :
          (s === 'f' || s === 'd' || s === 'v') ? 'partly stable' : 'unstable';
        groups[key] = groups[key] || { x: [], y: [], text: [] };
        groups[key].x.push(st.frequency_hz[i]);
        groups[key].y.push(st.order[i]);
        groups[key].text.push('order ' + st.order[i] + '<br>' + fmt(st.frequency_hz[i], 2) + ' Hz<br>ζ ' +
          fmt(100 * st.damping_ratio[i], 2) + ' %<br>' + s);
      });
      var style = {
        stable: { symbol: 'circle', color: '#1b7837', size: 7 },
        'partly stable': { symbol: 'diamond-open', color: '#4393c3', size: 6 },
        unstable: { symbol: 'circle-open', color: '#d6604d', size: 6 },
        'non-physical': { symbol: 'x-thin-open', color: '#999999', size: 5 }
      };
      var traces = Object.keys(groups).map(function (k) {
        return { type: 'scattergl', mode: 'markers', name: k, x: groups[k].x, y: groups[k].y, text: groups[k].text,
          hoverinfo: 'text', marker: { symbol: style[k].symbol, color: style[k].color, size: style[k].size } };
      });
      if (frf.sum_magnitude) traces.push({ type: 'scatter', mode: 'lines', name: 'sum of |FRF|', x: frf.frequency_hz,
        y: frf.sum_magnitude, yaxis: 'y2', line: { color: '#888', width: 1 }, hoverinfo: 'skip' });
      var mi = setup.mode_indicators || {};
      (mi.cmif || []).forEach(function (sv, i) {
        traces.push({ type: 'scatter', mode: 'lines', name: 'CMIF ' + (i + 1), x: mi.frequency_hz, y: sv, yaxis: 'y2',
          line: { color: i === 0 ? '#762a83' : '#c2a5cf', width: 1 }, hoverinfo: 'skip' });
      });
      if (mi.mmif) traces.push({ type: 'scatter', mode: 'lines', name: 'MMIF', x: mi.frequency_hz, y: mi.mmif,
        yaxis: 'y3', line: { color: '#e08214', width: 1, dash: 'dot' }, hoverinfo: 'skip' });
      var shapes = (setup.selected_hz || []).map(function (f) {
        return { type: 'line', x0: f, x1: f, yref: 'paper', y0: 0, y1: 1, line: { color: '#2166ac', dash: 'dash', width: 1 } };
      });
      chart(stab, traces, { height: 460, xaxis: { title: { text: 'frequency (Hz)' } },
        yaxis: { title: { text: 'model order' } },
        yaxis2: { title: { text: mi.cmif ? 'sum |H|, CMIF' : 'sum |H|' }, overlaying: 'y', side: 'right', type: 'log',
          showgrid: false },
        yaxis3: { overlaying: 'y', side: 'right', range: [0, 1.05], visible: false },
        shapes: shapes });
    } else {
      unavailable(stab, 'Stabilisation diagram');
    }

    // Measured FRFs with the synthesised fit.
    var fs = section(wrap, 'FRFs: measured and synthesised — ' + setup.name,
      'Measured accelerance (H1) and the FRF synthesised from the fitted poles (least squares residues with upper and ' +
      'lower residual terms, inside the fit band). Pick any FRF from the list.');
    if (frf.frfs && frf.frfs.length) {
      var select = el('select', { 'aria-label': 'FRF' });
      frf.frfs.forEach(function (item, i) { select.appendChild(el('option', { value: String(i), text: item.label })); });
      fs.appendChild(el('label', null, ['FRF (response / reference): ', select]));
      var frfTraces = function (i) {
        var item = frf.frfs[i];
        return [
          { type: 'scatter', mode: 'lines', name: 'measured |H|', x: frf.frequency_hz, y: item.magnitude, line: { color: '#2166ac' } },
          { type: 'scatter', mode: 'lines', name: 'synthesised |H|', x: frf.frequency_hz, y: item.fit_magnitude,
            line: { color: '#d6604d', dash: 'dash' } },
          { type: 'scatter', mode: 'lines', name: 'measured phase', x: frf.frequency_hz, y: item.phase_deg, yaxis: 'y2',
            line: { color: '#2166ac', width: 1 }, showlegend: false },
          { type: 'scatter', mode: 'lines', name: 'synthesised phase', x: frf.frequency_hz, y: item.fit_phase_deg,
            yaxis: 'y2', line: { color: '#d6604d', width: 1, dash: 'dash' }, showlegend: false }
        ];
      };
      var frfLayout = { height: 460, xaxis: { title: { text: 'frequency (Hz)' }, anchor: 'y2' },
        yaxis: { title: { text: '|H| (' + (frf.unit || '') + ')' }, type: 'log', domain: [0.35, 1] },
        yaxis2: { title: { text: 'phase (°)' }, domain: [0, 0.28], range: [-180, 180], dtick: 90 } };
      var frfDiv = chart(fs, frfTraces(0), frfLayout);
      select.addEventListener('change', function () { Plotly.react(frfDiv, frfTraces(Number(select.value)), frfLayout); });
    } else {
      unavailable(fs, 'FRFs');
    }
    if (setup.rejected && setup.rejected.length) {
      // One row per rejected impact and reason, with the FRFs it was dropped from.
      var byImpact = {};
      var order = [];
      setup.rejected.forEach(function (r) {
        var ref = r.reference || '';
        var key = ref + '|' + r.impact + '|' + r.reason;
        if (!byImpact[key]) { byImpact[key] = { ref: ref, impact: r.impact, reason: r.reason, n: 0 }; order.push(key); }
        byImpact[key].n += 1;
      });
      fs.appendChild(el('p', { text: 'Impacts rejected by the quality checks (never dropped silently):' }));
      table(fs, ['reference', 'impact', 'FRFs affected', 'reason'], order.map(function (k) {
        var r = byImpact[k]; return [r.ref, r.impact, r.n, r.reason];
      }), 'small');
    }

    // MAC matrices.
    var macs = section(wrap, 'MAC matrix — ' + setup.name,
      'Modal assurance criterion between the test modes (rows) and the model modes (columns), on the shared DOFs.');
    var macRow = el('div', { 'class': 'row' });
    macs.appendChild(macRow);
    [['mac_before', 'nominal model'], ['mac_after', 'updated model']].forEach(function (pair) {
      var m = setup[pair[0]] || {};
      var cell = el('div', { 'class': 'col' }, [el('h3', { text: 'test vs ' + pair[1] +
        (m.shared_dofs ? ' (' + m.shared_dofs + ' DOFs)' : '') })]);
      macRow.appendChild(cell);
      if (!m.values) { unavailable(cell, 'MAC vs ' + pair[1]); return; }
      var z = m.values.slice().reverse();
      var annotations = [];
      z.forEach(function (row, i) {
        row.forEach(function (v, j) {
          annotations.push({ x: m.model[j], y: m.test[m.test.length - 1 - i], text: v.toFixed(2), showarrow: false,
            font: { color: v > 0.6 ? 'white' : 'black', size: 10 } });
        });
      });
      chart(cell, [{ type: 'heatmap', z: z, x: m.model, y: m.test.slice().reverse(), zmin: 0, zmax: 1,
        colorscale: [[0, '#f7fbff'], [0.5, '#6baed6'], [1, '#08306b']], colorbar: { title: { text: 'MAC' } } }],
        { height: 380, annotations: annotations, margin: { l: 110, r: 20, t: 20, b: 90 } }, 'half');
    });

    // Validation tables.
    var val = section(wrap, 'Validation tables — ' + setup.name,
      'Agreement = 100·(1 − |f_model − f_test| / f_model), as in the reference thesis (Tables 7.7, 7.8).');
    var valRow = el('div', { 'class': 'row' });
    val.appendChild(valRow);
    [['correlation_before', 'before (nominal model)'], ['correlation_after', 'after (updated model)']].forEach(function (pair) {
      var c = setup[pair[0]] || {};
      var cell = el('div', { 'class': 'col' }, [el('h3', { text: pair[1] })]);
      valRow.appendChild(cell);
      if (!c.pairs) { unavailable(cell, 'Correlation ' + pair[1]); return; }
      table(cell, ['test mode', 'model mode', 'f test (Hz)', 'ζ test (%)', 'f model (Hz)', 'agreement %', 'MAC', 'remark'],
        c.pairs.map(function (p) {
          return [p.test_mode, p.model_mode, fmt(p.test_frequency_hz, 1), fmt(100 * p.test_damping_ratio, 2),
            fmt(p.model_frequency_hz, 1), fmt(p.agreement_pct, 1), fmt(p.mac, 3), p.remark || ''];
        }));
      if (c.summary) cell.appendChild(el('p', { 'class': 'note', text: 'mean agreement ' + fmt(c.summary.mean_agreement_pct, 1) +
        ' %, min ' + fmt(c.summary.min_agreement_pct, 1) + ' %, mean MAC ' + fmt(c.summary.mean_mac, 3) +
        '; unpaired test modes: ' + ((c.unpaired_test || []).length) + ', unpaired model modes: ' +
        ((c.unpaired_model || []).length) }));
    });

    // Test modes with their 1-sigma from the fit (ema fit's ML refinement).
    var tm = setup.test_mode_table || {};
    var tms = section(wrap, 'Test modes — ' + setup.name,
      'Fitted modes, f ± σ and ζ ± σ: 1σ of the estimate from the data\'s own noise (Fisher information of the ' +
      'maximum-likelihood fit).' + (tm.refinement ? ' Refinement: ' + tm.refinement.termination + ', noise from ' +
      tm.refinement.noise_source + '.' : ''));
    if (tm.modes && tm.modes.length) {
      var pm = function (v, s, scale, digits) {
        return fmt(v === null ? v : scale * v, digits) + (s === null || s === undefined ? '' : ' ± ' +
          Number(scale * s).toPrecision(2));
      };
      table(tms, ['mode', 'f ± σ (Hz)', 'ζ ± σ (%)', 'MPC', 'MPD (deg)', 'MCF'], tm.modes.map(function (m, i) {
        return [i + 1, pm(m.frequency_hz, m.frequency_std_hz, 1, 3), pm(m.damping_ratio, m.damping_ratio_std, 100, 3),
          fmt(m.mpc, 3), fmt(m.mpd_deg, 1), fmt(m.mcf, 3)];
      }));
      (tm.dropped || []).forEach(function (d) {
        tms.appendChild(el('p', { 'class': 'note', text: 'Pole at ' + fmt(d.frequency_hz, 2) + ' Hz dropped: ' + d.reason }));
      });
    } else {
      unavailable(tms, 'Test modes');
    }

    // Animated mode shapes on the test geometry.
    var ms = section(wrap, 'Mode shapes — ' + setup.name,
      'Test mode shapes animated on the test geometry (real part of the shape × cos ωt + imaginary part × sin ωt). ' +
      'Drag to rotate.');
    var sh = setup.shapes || {};
    if (sh.modes && sh.modes.length && sh.nodes && sh.nodes.length) {
      var modeSelect = el('select', { 'aria-label': 'mode' });
      sh.modes.forEach(function (m, i) {
        modeSelect.appendChild(el('option', { value: String(i), text: 'mode ' + (i + 1) + ': ' + fmt(m.frequency_hz, 1) +
          ' Hz, ζ ' + fmt(100 * m.damping_ratio, 2) + ' %' }));
      });
      ms.appendChild(el('label', null, ['Mode: ', modeSelect]));
      var span = 0;
      ['x', 'y', 'z'].forEach(function (a) {
        var v = sh.nodes.map(function (n) { return n[a]; });
        span = Math.max(span, Math.max.apply(null, v) - Math.min.apply(null, v));
      });
      var amplitude = 0.25 * (span || 1);
      var current = 0;
      var phase = 0;
      var positions = function (mode, t) {
        var c = Math.cos(t), s = Math.sin(t);
        var shape = sh.modes[mode].shape;
        var xs = [], ys = [], zs = [], lx = [], ly = [], lz = [];
        sh.nodes.forEach(function (n, i) {
          var u = shape[i];
          xs.push(n.x + amplitude * (u[0] * c - u[3] * s));
          ys.push(n.y + amplitude * (u[1] * c - u[4] * s));
          zs.push(n.z + amplitude * (u[2] * c - u[5] * s));
        });
        (sh.lines || []).forEach(function (l) {
          lx.push(xs[l[0]], xs[l[1]], null); ly.push(ys[l[0]], ys[l[1]], null); lz.push(zs[l[0]], zs[l[1]], null);
        });
        return { xs: xs, ys: ys, zs: zs, lx: lx, ly: ly, lz: lz };
      };
      var undeformed = positions(0, Math.PI / 2);
      var p0 = positions(0, 0);
      var restX = sh.nodes.map(function (n) { return n.x; });
      var restY = sh.nodes.map(function (n) { return n.y; });
      var restZ = sh.nodes.map(function (n) { return n.z; });
      var restL = { x: [], y: [], z: [] };
      (sh.lines || []).forEach(function (l) {
        restL.x.push(restX[l[0]], restX[l[1]], null); restL.y.push(restY[l[0]], restY[l[1]], null);
        restL.z.push(restZ[l[0]], restZ[l[1]], null);
      });
      void undeformed;
      var lim = function (v) { var lo = Math.min.apply(null, v), hi = Math.max.apply(null, v); return [lo - amplitude * 1.3, hi + amplitude * 1.3]; };
      var shapeDiv = chart(ms, [
        { type: 'scatter3d', mode: 'lines', name: 'at rest', x: restL.x, y: restL.y, z: restL.z,
          line: { color: '#bbbbbb', width: 2 }, hoverinfo: 'skip' },
        { type: 'scatter3d', mode: 'lines', name: 'deformed', x: p0.lx, y: p0.ly, z: p0.lz,
          line: { color: '#2166ac', width: 5 }, hoverinfo: 'skip' },
        { type: 'scatter3d', mode: 'markers', name: 'test points', x: p0.xs, y: p0.ys, z: p0.zs,
          text: sh.nodes.map(function (n) { return 'node ' + n.id; }), hoverinfo: 'text',
          marker: { size: 4, color: '#d6604d' } }
      ], { height: 520, scene: { aspectmode: 'data', xaxis: { range: lim(restX), title: { text: 'X (m)' } },
        yaxis: { range: lim(restY), title: { text: 'Y (m)' } }, zaxis: { range: lim(restZ), title: { text: 'Z (m)' } } },
        margin: { l: 0, r: 0, t: 10, b: 10 } });
      var refresh = null;
      modeSelect.addEventListener('change', function () {
        current = Number(modeSelect.value);
        clearTimeout(refresh);  // the printed picture follows the mode picked
        refresh = setTimeout(function () { snapshot(shapeDiv); }, 300);
      });
      var animating = false;
      var step = function () {
        if (!shapeDiv.getAttribute('data-rendered') || animating) return;
        animating = true;
        phase += Math.PI / 12;
        var p = positions(current, phase);
        Plotly.restyle(shapeDiv, { x: [p.lx, p.xs], y: [p.ly, p.ys], z: [p.lz, p.zs] }, [1, 2])
          .then(function () { animating = false; }, function () { animating = false; });
      };
      // '#still' in the URL (screenshots) keeps the shape at rest.
      if (location.hash.indexOf('still') < 0) setInterval(step, 90);
    } else {
      unavailable(ms, 'Mode shapes on the test geometry');
    }
  });

  drawAmplitude(data.amplitude);

  if (data.files && data.files.length) {
    var files = section(main, 'Files written by this run');
    files.appendChild(el('ul', { 'class': 'files' }, data.files.map(function (f) { return el('li', null, [el('code', { text: f })]); })));
  }

  // Printing. Chromium runs 'beforeprint' while the page still has the window's layout, then lays
  // the page out at the paper's printable width with no script in between: every 2D chart is
  // redrawn at that width first (A4 less the 12 mm margins of report.css: 186 mm = 703 CSS px), and
  // back to the window's width afterwards. A 3D (WebGL) chart does not print: each one keeps a
  // picture of itself at the page's width (refreshed when it changes), which print shows instead.
  var PRINT_WIDTH = 700;
  function is3d(div) { return !!(div._fullLayout && div._fullLayout._has && div._fullLayout._has('gl3d')); }
  function snapshot(div) {
    if (!is3d(div) || !div.getAttribute('data-rendered')) return Promise.resolve();
    var height = (div._fullLayout && div._fullLayout.height) || 420;
    return Plotly.toImage(div, { format: 'png', width: PRINT_WIDTH, height: height }).then(function (url) {
      var img = div.nextSibling && div.nextSibling.className === 'print-snapshot' ? div.nextSibling :
        div.parentNode.insertBefore(el('img', { 'class': 'print-snapshot', alt: chartTitle(div) }), div.nextSibling);
      img.src = url;
      div.classList.add('has-print-snapshot');
    }, function (e) {  // no picture: print shows the live chart (blank where WebGL does not print)
      body.setAttribute('data-print-snapshot-error', String(e && e.message || e));
    });
  }
  var PRINT_MAX_HEIGHT = 640;  // a tall chart (the coherence map) still shares its page with its heading
  window.addEventListener('beforeprint', function () {
    charts.forEach(function (div) {
      if (is3d(div)) return;
      var height = div.layout.height;
      div.setAttribute('data-screen-height', height || '');
      Plotly.relayout(div, { width: PRINT_WIDTH, height: height ? Math.min(height, PRINT_MAX_HEIGHT) : height });
    });
  });
  window.addEventListener('afterprint', function () {
    charts.forEach(function (div) {
      if (is3d(div)) return;
      var height = Number(div.getAttribute('data-screen-height')) || div.layout.height;
      Plotly.relayout(div, { width: null, height: height }).then(function () { Plotly.Plots.resize(div); });
    });
  });
  // ---- amplitude dependence (ema amplitude --json; docs/amplitude.md) ----
  function drawAmplitude(amp) {
    if (!amp || !amp.modes || !amp.modes.length) return;
    var unit = amp.level_kind === 'response' ? 'response level' :
      (amp.level_kind === 'rms_force' ? 'RMS force (N)' : 'peak force (N)');
    var sec = section(main, 'Frequency and damping against level',
      'Each mode followed over the excitation levels; error bars are the fit\'s 1σ where known. ' +
      'Trends are tested against each point\'s σ and a repeatability floor (docs/amplitude.md).');
    table(sec, ['mode', 'frequency', 'change %', 'damping', 'ζ factor', 'reading'], amp.modes.map(function (m) {
      return [m.mode, m.frequency_trend, fmt(m.frequency_change_pct, 3), m.damping_trend,
        fmt(m.damping_ratio_factor, 2), m.reading];
    }), 'small');
    amp.modes.forEach(function (m) {
      var x = m.levels.map(function (p) { return p.level; });
      var bar = function (key, scale) {
        var v = m.levels.map(function (p) { return p[key] === null || p[key] === undefined ? 0 : p[key] * scale; });
        return { type: 'data', array: v, visible: v.some(function (e) { return e > 0; }) };
      };
      chart(sec, [
        { x: x, y: m.levels.map(function (p) { return p.frequency_hz; }), name: 'f (Hz)', mode: 'lines+markers',
          error_y: bar('frequency_std_hz', 1) },
        { x: x, y: m.levels.map(function (p) { return 100 * p.damping_ratio; }), name: 'ζ (%)', yaxis: 'y2',
          mode: 'lines+markers', error_y: bar('damping_ratio_std', 100) }
      ], {
        height: 360, margin: { l: 60, r: 60, t: 40, b: 50 },
        title: { text: 'mode ' + m.mode + ': frequency ' + m.frequency_trend + ', damping ' + m.damping_trend },
        xaxis: { title: { text: unit }, type: 'log' }, yaxis: { title: { text: 'frequency (Hz)' } },
        yaxis2: { title: { text: 'damping ratio (%)' }, overlaying: 'y', side: 'right', showgrid: false }
      });
    });
  }

  body.setAttribute('data-charts-expected', String(expected));
  Promise.all(pending).then(function () {
    body.setAttribute('data-charts-rendered', String(rendered));
    // The 3D charts' pictures for print, one after the other (in the background).
    charts.reduce(function (chain, div) { return chain.then(function () { return snapshot(div); }); }, Promise.resolve())
      .then(function () { body.setAttribute('data-print-snapshots', 'done'); });
    // Self-check of the download buttons (opened as report.html#export-check by the tests): every
    // chart exported as SVG (its text must hold the chart's title) and as PNG.
    if (window.location.hash !== '#export-check') return;
    var svg = 0, png = 0;
    return Promise.all(charts.map(function (div) {
      var title = chartTitle(div);
      return Promise.all([exportChart(div, 'svg', title), exportChart(div, 'png', title)]).then(function (urls) {
        if (decodeURIComponent(urls[0]).indexOf(title) >= 0) svg += 1;
        if (urls[1].indexOf('data:image/png;base64,') === 0 && urls[1].length > 1000) png += 1;
      });
    })).then(function () {
      body.setAttribute('data-export-svg', String(svg));
      body.setAttribute('data-export-png', String(png));
    });
  }).catch(function (e) { noteError(e); });
})();
