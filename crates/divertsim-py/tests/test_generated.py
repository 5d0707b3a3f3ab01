"""The analyses' Python functions are generated from the library's options types: the file
in the package is what the generator writes now, and the signatures carry the CLI's
defaults."""

import inspect
import json
import os
import pathlib

import divertsim
from divertsim import _codegen, _native

GENERATED = pathlib.Path(__file__).resolve().parents[1] / "python" / "divertsim" / "_analyses.py"


def test_the_generated_functions_are_current():
    want = _codegen.render(_native.registry())
    if os.environ.get("DIVERTSIM_BLESS") == "1":
        GENERATED.write_text(want, encoding="utf-8")
    have = GENERATED.read_text(encoding="utf-8")
    assert have == want, (
        "crates/divertsim-py/python/divertsim/_analyses.py is stale: rerun the tests with "
        "DIVERTSIM_BLESS=1 (or python -m divertsim._codegen) after changing an options type"
    )


def test_every_option_is_a_keyword_with_the_schema_default():
    for name, about, _sets, schema_text in _native.registry():
        props = json.loads(schema_text)["properties"]
        fn = getattr(divertsim, name)
        params = inspect.signature(fn).parameters
        assert fn.__doc__.startswith(about), name
        for key, p in props.items():
            assert params[key].kind is inspect.Parameter.KEYWORD_ONLY, (name, key)
            default = params[key].default
            want = p.get("default")
            assert (list(default) if isinstance(default, tuple) else default) == want, (name, key)
            assert key + ":" in fn.__doc__, (name, key)


def test_a_generated_default_gives_the_same_result_as_no_option():
    # The defaults written into the signatures are the options type's: passing them
    # explicitly changes nothing.
    a = divertsim.trigger("configs/paper/fig06.toml", speeds=[0.65, 1.3])
    b = divertsim.analyses.run("trigger", "configs/paper/fig06.toml", speeds=[0.65, 1.3])
    assert a.summary == b.summary and a.text == b.text
