"""FE models built from parts in Python (scipy.sparse / numpy) and test modes as dicts in `ema fit
--json`'s layout: the same model written as a model file with Matrix Market parts, and the same modes
as MODES.json, give the CLI's results to the last digit; bad input names the argument."""
import json
import types

import numpy as np
import pytest

import ema
from conftest import load_json, run_ema

sp = pytest.importorskip("scipy.sparse")

E, RHO, AREA, INERTIA = 210e9, 7850.0, 0.03 * 0.02, 0.03 * 0.02**3 / 12


def beam_element(length):
    """2D Euler-Bernoulli element along x, (ux, uz, ry) per end, ry about y (dw/dx = -ry)."""
    ea, ei = E * AREA / length, E * INERTIA
    k1, k2, k3, k4 = 12 * ei / length**3, 6 * ei / length**2, 4 * ei / length, 2 * ei / length
    return np.array([[ea, 0, 0, -ea, 0, 0], [0, k1, -k2, 0, -k1, -k2], [0, -k2, k3, 0, k2, k4],
                     [-ea, 0, 0, ea, 0, 0], [0, -k1, k2, 0, k1, k2], [0, -k2, k4, 0, k2, k3]])


def cantilever(softened=None, factor=1.0):
    """A cantilever of 8 elements (nodes 1..9, node 1 clamped) in four zone parts Z1..Z4 (group
    'zones'), lumped mass in [fe].mass, a 0.2 kg payload at the tip as a mass-only part."""
    n_el, length = 8, 0.1
    index = {(node, d): 3 * (node - 2) + j for node in range(2, n_el + 2) for j, d in enumerate(("ux", "uz", "ry"))}
    n = len(index)
    mass = np.zeros(n)
    parts = []
    for z in range(4):
        rows, cols, vals = [], [], []
        for e in (2 * z, 2 * z + 1):
            ids = [index.get((node, d), -1) for node in (e + 1, e + 2) for d in ("ux", "uz", "ry")]
            k = beam_element(length)
            for p, ip in enumerate(ids):
                for q, iq in enumerate(ids):
                    if ip >= 0 and iq >= 0:
                        rows.append(ip), cols.append(iq), vals.append(k[p, q])
            for node in (e + 1, e + 2):
                for d in ("ux", "uz"):
                    if (node, d) in index:
                        mass[index[node, d]] += RHO * AREA * length / 2
        k = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()  # duplicates add up
        name = f"Z{z + 1}"
        parts.append({"name": name, "group": "zones", "stiffness": k * (factor if name == softened else 1.0),
                      "uncertainty": 0.3})
    tip = sp.diags([0.2 if key in ((9, "ux"), (9, "uz")) else 0.0 for key in sorted(index, key=index.get)])
    parts.append({"name": "payload", "mass": tip.tocsc(), "uncertainty": 0.2})
    return {
        "name": "cantilever in parts",
        "dofs": sorted(index, key=index.get),
        "mass": sp.diags(mass),
        "parts": parts,
        "nodes": {node: (length * (node - 1), 0.0, 0.0) for node in range(2, n_el + 2)},
        "points": [{"id": 100 + node, "node": node} for node in (3, 5, 7, 9)],
        "damping": 0.01,
    }


def write_mtx(path, matrix):
    coo = sp.coo_matrix(matrix)
    lines = ["%%MatrixMarket matrix coordinate real general", f"{coo.shape[0]} {coo.shape[1]} {coo.nnz}"]
    lines += [f"{i + 1} {j + 1} {v!r}" for i, j, v in zip(coo.row, coo.col, coo.data)]
    path.write_text("\n".join(lines) + "\n")


def write_model_file(model, folder):
    """The same model as a model file (TOML + Matrix Market + CSV), numbers written exactly."""
    write_mtx(folder / "M.mtx", model["mass"])
    (folder / "dofs.csv").write_text("node,dof\n" + "".join(f"{node},{d}\n" for node, d in model["dofs"]))
    (folder / "nodes.csv").write_text("node,x,y,z\n" + "".join(f"{k},{x!r},{y!r},{z!r}\n"
                                                               for k, (x, y, z) in model["nodes"].items()))
    toml = [f'[model]\nname = "{model["name"]}"\n', f'[damping]\nratio = {model["damping"]!r}\n',
            '[fe]\nmass = "M.mtx"\ndofs = "dofs.csv"\nnodes = "nodes.csv"\n']
    for p in model["parts"]:
        toml.append(f'[[fe.part]]\nname = "{p["name"]}"\n' + (f'group = "{p["group"]}"\n' if "group" in p else ""))
        for key in ("stiffness", "mass"):
            if key in p:
                write_mtx(folder / f"{key}_{p['name']}.mtx", p[key])
                toml.append(f'{key} = "{key}_{p["name"]}.mtx"\n')
        toml.append(f'uncertainty = {p["uncertainty"]!r}\n')
    for pt in model["points"]:
        toml.append(f'[[point]]\nid = {pt["id"]}\nnode = {pt["node"]}\n')
    (folder / "model.toml").write_text("\n".join(toml))
    return folder / "model.toml"


def json_layout(modes, dirs=("+Z",), sigma=0.002):
    """Modes (a modes dict) in `ema fit --json`'s layout at the DOFs of `dirs` only, with a 1σ."""
    keep = [r for r, (_, d) in enumerate(modes["dofs"]) if d in dirs]
    return {"modes": [{"frequency_hz": float(f), "frequency_std_hz": sigma * float(f),
                       "damping_ratio": float(modes["damping_ratio"][i]),
                       "shape": [{"node": modes["dofs"][r][0], "dir": modes["dofs"][r][1],
                                  "value": [modes["shapes"][r, i].real, modes["shapes"][r, i].imag]} for r in keep]}
                      for i, f in enumerate(modes["frequency_hz"])]}


def test_model_from_parts_in_python_equals_the_model_file(tmp):
    model = cantilever()
    path = write_model_file(model, tmp)
    from_dict, from_file = ema.model_modes(model), ema.model_modes(str(path))
    assert len(from_dict["frequency_hz"]) > 4
    assert from_dict["frequency_hz"].tolist() == from_file["frequency_hz"].tolist()
    assert from_dict["dofs"] == from_file["dofs"] == [(p, d) for p in (103, 105, 107, 109) for d in ("+X", "+Y", "+Z")]
    assert np.array_equal(from_dict["shapes"], from_file["shapes"])
    # Any object with the keys as attributes, dense numpy matrices, a list of point nodes: the same model.
    dense = dict(model, mass=model["mass"].toarray(),
                 parts=[dict(p, **{k: p[k].toarray() for k in ("stiffness", "mass") if k in p}) for p in model["parts"]],
                 points=[{"id": p["id"], "node": p["node"]} for p in model["points"]])
    assert ema.model_modes(types.SimpleNamespace(**dense))["frequency_hz"].tolist() == from_file["frequency_hz"].tolist()
    by_node = ema.model_modes(dict(model, points=[3, 5, 7, 9]))
    assert [p for p, _ in by_node["dofs"][::3]] == [3, 5, 7, 9]
    assert by_node["frequency_hz"].tolist() == from_file["frequency_hz"].tolist()


def test_diagnose_parts_model_with_json_layout_modes_matches_cli(tmp):
    nominal = cantilever()
    test = json_layout(ema.model_modes(cantilever("Z3", 0.5), max_modes=4))
    model_file = write_model_file(nominal, tmp)
    (tmp / "MODES.json").write_text(json.dumps(test))
    run_ema("diagnose", model_file, "--test", tmp / "MODES.json", "--json", tmp / "diag.json")
    cli = load_json(tmp / "diag.json")
    py = ema.diagnose(nominal, {"": test})
    assert py["candidates"][0]["target"] == "zones/Z3"
    assert abs(py["candidates"][0]["parameters"]["factor"] - 0.5) < 0.01
    for key in ["candidates", "baseline", "effect_probabilities", "groups", "steps", "explanation", "modes",
                "options", "criterion", "residual_count", "test_modes"]:
        assert py[key] == cli[key], key
    # The test modes' σ are the ones given: 0.2 % of each frequency.
    assert [r["sigma_hz"] for r in py["modes"]] == [m["frequency_std_hz"] for m in test["modes"]]
    # A path to the same MODES.json, and the modes as a dict of arrays: the same diagnosis.
    assert ema.diagnose(nominal, str(tmp / "MODES.json"))["candidates"] == py["candidates"]
    arrays = ema.read_modes(tmp / "MODES.json")
    assert arrays["frequency_std_hz"].tolist() == [m["frequency_std_hz"] for m in test["modes"]]
    assert ema.diagnose(nominal, {"": arrays})["candidates"] == py["candidates"]
    assert ema.diagnose(nominal, test)["candidates"] == py["candidates"]  # one mode set alone: the nominal setup's
    # Options as the CLI's.
    single = ema.diagnose(nominal, {"": test}, max_effects=1, members=False)
    assert single["options"]["max_effects"] == 1 and single["options"]["members"] is False
    assert all("/" not in c["target"] for c in single["candidates"])


def test_bad_models_and_modes_name_the_argument():
    model = cantilever()
    n = len(model["dofs"])
    asymmetric = sp.lil_matrix(model["parts"][0]["stiffness"])
    asymmetric[0, 1] += 1.0e6
    with pytest.raises(ema.InputError, match=r"model\['parts'\]\[0\]\['stiffness'\]: entry \[0, 1\]"):
        ema.model_modes(dict(model, parts=[dict(model["parts"][0], stiffness=asymmetric)] + model["parts"][1:]))
    with pytest.raises(ema.InputError, match=r"model\['mass'\]: is 3x3 but model\['dofs'\] lists"):
        ema.model_modes(dict(model, mass=np.eye(3)))
    with pytest.raises(ema.InputError, match="unknown key 'springs'"):
        ema.model_modes(dict(model, springs=[]))
    with pytest.raises(ema.InputError, match=r"model\['parts'\]\[1\].*duplicate part name 'Z1'"):
        ema.model_modes(dict(model, parts=[model["parts"][0], model["parts"][0]]))
    negative = dict(model["parts"][0], stiffness=-model["parts"][0]["stiffness"])
    with pytest.raises(ema.InputError, match="not positive semi-definite"):
        ema.model_modes(dict(model, parts=[negative] + model["parts"][1:]))
    with pytest.raises(ema.InputError, match="dof 'uq'"):
        ema.model_modes(dict(model, dofs=[(2, "uq")] + model["dofs"][1:]))
    with pytest.raises(TypeError, match=r"model\['parts'\]\[0\]\['stiffness'\]: expected a scipy.sparse matrix"):
        ema.model_modes(dict(model, parts=[dict(model["parts"][0], stiffness="K.mtx")] + model["parts"][1:]))
    assert n == 24
    test = json_layout(ema.model_modes(model, max_modes=2))
    test["modes"][1]["shape"] = test["modes"][1]["shape"][:-1]
    with pytest.raises(ema.InputError, match=r"tests\['cold'\]: modes\[1\]\.shape: 3 DOFs but modes\[0\] lists 4"):
        ema.diagnose(model, {"cold": test})
    with pytest.raises(ema.InputError, match=r"tests\['cold'\].*finite"):
        ema.diagnose(model, {"cold": {"modes": [{"frequency_hz": float("nan"), "shape": []}]}})
    with pytest.raises(ValueError, match="criterion"):
        ema.diagnose(model, {"": json_layout(ema.model_modes(model, max_modes=2))}, "best")
