"""Issue 41: FEBio input that ended in an internal error or was silently dropped is refused
with one line naming the file, the element and its line."""

from __future__ import annotations

from pathlib import Path

import pytest

from tissuesim.cli import main
from tissuesim.febio import FebError, read_feb

MODELS = Path(__file__).parent / "models"


def refusal(tmp_path, text: str, model: str = "uniaxial_neo_hookean.feb") -> str:
    """The one-line FebError reading ``text`` (a changed copy of ``model``) gives."""
    feb = tmp_path / "bad.feb"
    feb.write_text(text)
    with pytest.raises(FebError) as info:
        read_feb(feb)
    said = str(info.value)
    assert "\n" not in said and said.startswith(f"{feb}:")
    return said


def line_of(text: str, needle: str) -> int:
    return next(i for i, s in enumerate(text.splitlines(), 1) if needle in s)


BAD_IDS = {
    "lc": ('lc="1"', 'lc="one"', "<value>", 'lc="one": a load curve id'),
    "node": ('<node id="5">', '<node id="five">', "<node>", 'id="five": a node id'),
    "elem": ('<elem id="1">', '<elem id="1a">', "<elem>", 'id="1a": an element id'),
    "curve": ('<load_controller id="1"', '<load_controller id="x"', "<load_controller>", "id"),
}


@pytest.mark.parametrize("case", sorted(BAD_IDS))
def test_an_id_that_is_not_an_integer_names_the_element_and_line(case, tmp_path):
    old, new, tag, message = BAD_IDS[case]
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    assert old in text
    text = text.replace(old, new, 1)
    said = refusal(tmp_path, text)
    assert f"bad.feb:{line_of(text, new)} {tag}" in said and message in said
    assert "must be an integer" in said


def test_an_unknown_encoding_is_one_line(tmp_path, capsys):
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    head, rest = text.split("\n", 1)
    assert head.startswith("<?xml")
    feb = tmp_path / "bad.feb"
    feb.write_text('<?xml version="1.0" encoding="klingon"?>\n' + rest)
    assert main(["convert", str(feb), str(tmp_path / "scene.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "internal error" not in err
    assert f"{feb}:1 <?xml?>: unknown encoding 'klingon'" in err and "UTF-8" in err


SILENT = {
    # a condition on an empty set fixed nothing: the block slid away with no reaction
    "empty set": (
        '<NodeSet name="x0">1,4,7,10,13,16,19,22,25</NodeSet>',
        '<NodeSet name="x0"></NodeSet>',
        '<bc name="symmetry_x"',
        "<bc>",
        "node set 'x0' is empty",
    ),
    # a misspelt lc dropped the load curve: the full load acted from the first step
    "misspelt lc": ('<value lc="1">', '<value lcc="1">', "<value lcc", "<value>", "lc?"),
    "unknown attribute": (
        '<SolidDomain name="block" mat="tissue"/>',
        '<SolidDomain name="block" mat="tissue" elem_type="UT4"/>',
        "<SolidDomain",
        "<SolidDomain>",
        "elem_type",
    ),
    "bc attribute": (
        'node_set="x0" type="zero displacement">',
        'node_set="x0" typ="x" type="zero displacement">',
        'typ="x"',
        "<bc>",
        'attribute typ="x" is not one tissuesim reads on <bc>: correct or remove it',
    ),
    # a parameter given twice kept the second without a word
    "parameter twice": ("<E>10000</E>", "<E>10000</E>\n      <E>20000</E>", "<E>2", "<E>", "twice"),
    "bc parameter twice": (
        "<dof>x</dof>",
        "<dof>x</dof>\n      <dof>y</dof>",
        "<dof>y",
        "<dof>",
        "<dof> is given twice in <bc> (first at line",
    ),
    # convert wrote density = -1000, which run then refused
    "density": (
        "<density>1000</density>",
        "<density>-1000</density>",
        "<density>",
        "<density>",
        "density -1000: a density must be > 0",
    ),  # fmt: skip
}


@pytest.mark.parametrize("case", sorted(SILENT))
def test_dropped_or_doubled_input_is_refused_with_its_line(case, tmp_path):
    old, new, needle, tag, message = SILENT[case]
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    assert old in text
    text = text.replace(old, new, 1)
    said = refusal(tmp_path, text)
    assert f"bad.feb:{line_of(text, needle)} {tag}" in said and message in said, said


def test_convert_writes_no_scene_that_run_refuses(tmp_path, capsys):
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    feb = tmp_path / "bad.feb"
    feb.write_text(text.replace("<density>1000</density>", "<density>-1000</density>"))
    assert main(["convert", str(feb), str(tmp_path / "scene.toml")]) == 2
    assert "density" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.feb"]


def test_labels_and_noted_sections_are_not_refused():
    # name / id only label elements; <Output>'s plotfile attributes belong to a noted section
    for model in sorted(MODELS.glob("*.feb")):
        read_feb(model)


def test_reading_is_linear_in_the_number_of_text_chunks(tmp_path):
    # every line is a text chunk for the XML parser: the reader appended each one to the
    # element's string (O(n^2): a 200k-id set one id per line took 18-27 s, these 400k lines
    # 25 s and more); joined once they take a fraction of a second
    import time

    from tissuesim.febio.xml import parse_feb

    n = 400_000
    feb = tmp_path / "big_set.feb"
    ids = "".join(f"{i},\n" for i in range(1, n + 1))
    feb.write_text(f'<febio_spec version="4.0"><Mesh><NodeSet name="s">\n{ids}</NodeSet></Mesh>'
                   "</febio_spec>\n")  # fmt: skip
    start = time.perf_counter()
    root = parse_feb(feb)
    elapsed = time.perf_counter() - start
    text = root.children[0].children[0].text
    assert text.count(",") == n and text.startswith("1,") and text.endswith(f"{n},")
    assert elapsed < 5.0, f"{elapsed:.1f} s to parse {n} lines"


def test_fast_and_slow_paths_read_the_same_mesh(tmp_path):
    # nodes and elements are parsed all at once; odd spacing, ';' separators and a trailing
    # comma take the element-by-element path, with the same result
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    fast = read_feb(MODELS / "uniaxial_neo_hookean.feb")
    odd = text.replace('<node id="2">0.5,0.0,0.0</node>', '<node id="2"> 0.5; 0.0 ,0.0 </node>')
    odd = odd.replace('<elem id="1">1,2,5,4,10,11,14,13</elem>',
                      '<elem id="1"> 1, 2,5,4,10,11,14,13,</elem>')  # fmt: skip
    assert odd != text
    feb = tmp_path / "odd.feb"
    feb.write_text(odd)
    slow = read_feb(feb)
    assert (slow.nodes == fast.nodes).all()
    assert (slow.parts["block"][1] == fast.parts["block"][1]).all()


@pytest.mark.parametrize("steps", ["-4", "0", "", "2,3"])
def test_time_steps_are_refused_at_their_feb_line(steps, tmp_path, capsys):
    # -4 was refused by the converted scene, naming a deleted temporary model.toml
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    text = text.replace("<time_steps>4</time_steps>", f"<time_steps>{steps}</time_steps>")
    feb = tmp_path / "bad.feb"
    feb.write_text(text)
    out = tmp_path / "out"
    assert main(["run", str(feb), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"bad.feb:{line_of(text, '<time_steps>')} <time_steps>: time_steps must be" in err
    assert "tissuesim-febio-" not in err and ".toml" not in err


def test_a_converted_scene_refused_names_the_model_not_a_temporary_file(tmp_path, monkeypatch):
    import tissuesim.scene.loader as loader
    from tissuesim.errors import SceneError
    from tissuesim.febio import load_febio

    def refuse(path):  # whatever the scene refuses names its (temporary) file
        raise SceneError(f"{path} [run]: steps must be an integer >= 0, not -4")

    monkeypatch.setattr(loader, "load_scene", refuse)
    with pytest.raises(SceneError) as info:
        load_febio(MODELS / "uniaxial_neo_hookean.feb")
    said = str(info.value)
    assert said.startswith(f"{MODELS / 'uniaxial_neo_hookean.feb'} (its converted scene) [run]")
    assert "tissuesim-febio-" not in said


def test_reading_leaves_the_garbage_collector_as_it_was(tmp_path):
    # read_feb pauses Python's cyclic collector (it rescanned a large model's XML tree again
    # and again: half of a 1e6-node read); it must be back on afterwards, an error or not
    import gc

    assert gc.isenabled()
    read_feb(MODELS / "uniaxial_neo_hookean.feb")
    assert gc.isenabled()
    bad = tmp_path / "bad.feb"
    bad.write_text('<febio_spec version="4.0"><Rigid/></febio_spec>')
    with pytest.raises(FebError):
        read_feb(bad)
    assert gc.isenabled()
    gc.disable()
    try:
        read_feb(MODELS / "uniaxial_neo_hookean.feb")
        assert not gc.isenabled()  # left off when it was off
    finally:
        gc.enable()


def test_a_solver_tuning_given_twice_is_a_note_an_integrator_parameter_is_refused(tmp_path):
    """FEBio keeps the last of a <solver> setting given twice (bt02, dy16, dy17 give lstol
    twice): a tuning setting is one note; Newmark's beta twice is ambiguous and refused."""
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    path = tmp_path / "twice.feb"
    path.write_text(text.replace('<solver type="solid">', '<solver type="solid">\n'
                                 "      <lstol>0</lstol>\n      <lstol>0.9</lstol>"))  # fmt: skip
    model = read_feb(path)
    assert sum("lstol" in n for n in model.notes) == 1
    path.write_text(text.replace('<solver type="solid">', '<solver type="solid">\n'
                                 "      <beta>0.25</beta>\n      <beta>0.3</beta>"))  # fmt: skip
    with pytest.raises(FebError, match="<beta> is given twice in <solver>"):
        read_feb(path)


def test_a_body_load_with_a_curve_per_component_is_a_load_per_component(tmp_path):
    """FEBio 3's const body load may give x, y and z each its own curve (dy05): one body
    force per component that is not zero, each with its curve; the force applied is the
    negative of the vector given (FEBio adds -rho f: z = -9.81 pushes up)."""
    text = (MODELS / "uniaxial_neo_hookean.feb").read_text()
    body = ('  <Loads>\n    <body_load type="const">\n      <x lc="1">2</x>\n'
            '      <y lc="1">0</y>\n      <z lc="2">-9.81</z>\n    </body_load>\n  </Loads>\n'
            "  <LoadData>")  # fmt: skip
    text = text.replace("  <LoadData>", body, 1)
    text = text.replace(
        "  </LoadData>",
        '    <load_controller id="2" type="loadcurve">\n      <points>\n        <pt>0,1</pt>\n'
        "        <pt>1,1</pt>\n      </points>\n    </load_controller>\n  </LoadData>",
    )
    path = tmp_path / "body.feb"
    path.write_text(text)
    loads = read_feb(path).body_loads
    assert [(load.value.tolist(), load.curve) for load in loads] == [
        ([-2.0, 0.0, 0.0], 1),
        ([0.0, 0.0, 9.81], 2),
    ]


@pytest.mark.parametrize("value", ["0", "1"])
def test_contact_on_the_shells_front_faces_is_read_their_back_faces_refused(value, tmp_path):
    """shell_bottom_primary / _secondary 0 (FEBio's default: the front faces, tissuesim's
    shells' contact faces) read; 1 refused in one line."""
    text = (MODELS / "contact_touching.feb").read_text()
    path = tmp_path / "bottom.feb"
    old = "<fric_coeff>0.01</fric_coeff>"
    assert old in text
    path.write_text(text.replace(old, f"{old}\n      <shell_bottom_primary>{value}"
                                 "</shell_bottom_primary>"))  # fmt: skip
    if value == "0":
        assert read_feb(path).contacts
    else:
        with pytest.raises(FebError, match="back faces"):
            read_feb(path)
