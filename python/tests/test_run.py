"""ema.run: the typed pipeline of `ema run` bound as it is (pipeline::Run), against the CLI's files."""
import ema
import pytest

from conftest import SOURCE, load_json, run_ema


def test_run_gives_the_numbers_of_the_cli_run(tmp):
    project = SOURCE / "samples" / "guideway" / "project.toml"
    run_ema("run", project, "-o", tmp / "cli", "--no-report")
    py = ema.run(str(project), output=tmp / "cli")
    assert [s["status"] for s in py["steps"]] == ["done"] * len(py["steps"])
    assert [t["name"] for t in py["tests"]] == ["stud-5um", "stud-9um"]
    # The same stages and codecs: DIAG.json and each test's modes and correlations key by key.
    cli = load_json(tmp / "cli" / "diagnosis.json")
    assert set(py["diagnosis"]) == set(cli)
    for key in cli:
        assert py["diagnosis"][key] == cli[key], key
    for test in py["tests"]:
        assert test["modes"] == load_json(tmp / "cli" / test["name"] / "modes.json")
        assert test["frf"] == load_json(tmp / "cli" / test["name"] / "frf.json")
        for when in ("before", "after"):
            assert test[f"correlation_{when}"] == load_json(tmp / "cli" / test["name"] / f"correlation-{when}.json")
    # The thesis's story in numbers: rank 1 the mount compliance (a Hertz contact with the air film),
    # the mean agreement from under 75 % to above 99 %.
    rank1 = py["diagnosis"]["candidates"][0]
    assert (rank1["kind"], rank1["target"]) == ("series_compliance", "bearings")
    assert py["mean_agreement_pct_before"] < 75.0 < 99.0 < py["mean_agreement_pct_after"]
    finding = py["diagnosis"]["findings"][0]
    assert [s["setup"] for s in finding["springs"]] == ["stud-5um", "stud-9um"]
    assert finding["springs"][0]["per_spring_n_per_m"] == pytest.approx(2.80e6, rel=0.005)
    assert isinstance(py, ema.Result)


def test_run_refuses_the_old_args_and_names_the_file(tmp):
    project = SOURCE / "samples" / "guideway" / "project.toml"
    text = project.read_text().replace('model = "model.toml"', f'model = "{project.parent / "model.toml"}"')
    text = text.replace('"data/', f'"{project.parent / "data"}/')
    (tmp / "old.toml").write_text(text + "\n[diagnose]\nargs = [\"--max-effects\", \"1\"]\n")
    with pytest.raises(ema.UsageError, match="old.toml.*args"):
        ema.run(str(tmp / "old.toml"))
