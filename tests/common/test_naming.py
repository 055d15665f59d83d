"""The naming scheme: every name the URDF and MJCF hold is parsed back to its body."""

import xml.etree.ElementTree as ET

import pytest

from assembler_pin.common.naming import LEG_PARTS, names, parse_name


def test_builders_and_parser_are_inverse():
    for j in range(3):
        for i in range(6):
            assert parse_name(names.leg(j, i)).indices == (j, i)
            for part in LEG_PARTS:
                parsed = parse_name(names.leg(j, i, part))
                assert (parsed.kind, parsed.indices) == (part, (j, i))
    assert parse_name(names.plate(7)).indices == (7,)
    assert parse_name(names.payload).kind == "payload"


@pytest.mark.parametrize("bad", ["plate_", "sp1_leg", "sp0_leg2_wheel", "platex", "sp0_plate"])
def test_foreign_names_are_refused(bad):
    with pytest.raises(ValueError, match="not a plate, payload or leg name"):
        parse_name(bad)


def test_every_urdf_link_of_a_leg_or_plate_parses(tmp_path):
    from assembler_pin import load_config
    from assembler_pin.model.urdf import assembler_urdf

    root = ET.fromstring(assembler_urdf(load_config(None)))
    links = [e.get("name") for e in root.iter("link")]
    parsed = [parse_name(n) for n in links if n.startswith("plate_") or "_leg" in n]
    legs = {p.indices for p in parsed if p.kind != "plate"}
    plates = {p.indices for p in parsed if p.kind == "plate"}
    assert legs == {(j, i) for j in range(4) for i in range(6)}
    assert plates == {(k,) for k in range(5)}
