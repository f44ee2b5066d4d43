"""Every EDS coforge exports loads in python-canopen (the master used for interoperability
tests), and every object and sub-index of the spec appears there with the right data type,
access type, name and default, with $NODEID resolved for sample node IDs."""

import json
import subprocess

import canopen
import pytest
from host import COFORGE, ROOT

SPECS = sorted((ROOT / "spec").glob("*.yaml"))
NODE_IDS = [1, 0x22, 127]


def coforge(*args):
    return subprocess.run([COFORGE, *map(str, args)], check=True, capture_output=True, text=True).stdout


def cases():
    for spec in SPECS:
        info = json.loads(coforge("info", spec))
        for eds in info["eds"]:
            for node_id in NODE_IDS:
                yield pytest.param(spec, eds["mode"], node_id, id=f"{spec.stem}-{eds['mode'] or 'single'}-{node_id}")


def test_every_spec_is_exported():
    assert [s.name for s in SPECS] == ["canopenia.yaml", "co401gw1.yaml", "co401memory1.yaml", "cr3101.yaml"]


@pytest.mark.parametrize("spec,mode,node_id", list(cases()))
def test_eds_imports_with_every_entry(tmp_path, spec, mode, node_id):
    mode_args = ["--mode", mode] if mode else []
    eds_path = tmp_path / "device.eds"
    coforge("eds", spec, *mode_args, "-o", eds_path)
    model = json.loads(coforge("model", spec, "--node-id", node_id, *mode_args))
    od = canopen.import_od(str(eds_path), node_id=node_id)

    assert model["entries"], "the model has entries"
    checked = 0
    for entry in model["entries"]:
        where = f"{entry['index']:04X}.{entry['sub']} {entry['name']}"
        assert entry["index"] in od, f"{where} missing from the EDS"
        obj = od[entry["index"]]
        if entry["dummy"]:
            assert obj.data_type == entry["data_type"], where
            continue
        var = obj if entry["object_kind"] in ("VAR", "DOMAIN") else obj[entry["sub"]]
        assert isinstance(var, canopen.objectdictionary.ODVariable), where
        assert var.subindex == entry["sub"], where
        assert var.data_type == entry["data_type"], where
        assert var.access_type == entry["access"], where
        assert var.name == " ".join(entry["name"].split()), where
        if entry["default"] is None:
            assert var.default is None, f"{where}: no default expected, EDS gives {var.default!r}"
        elif isinstance(entry["default"], float):
            assert var.default == pytest.approx(entry["default"]), where
        else:
            assert var.default == entry["default"], f"{where}: EDS default {var.default!r} != spec {entry['default']!r}"
        checked += 1
    assert checked > 10
