"""Hidden code (gpsaccel.assignments.hidden): every way of running text the notebook does not
show is named; honest answers, and code run from literal text, are not."""

from __future__ import annotations

import ast
import base64
import bz2
import codecs
import marshal
import pickle
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from gpsaccel.assignments import hidden

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
import _similarity_classes as sc  # noqa: E402

ANSWER = "def average_nees(x_true, x_hat, P):\n    return 1.0\n"
B64 = base64.b64encode(zlib.compress(ANSWER.encode())).decode()

#: (packing, what the finding must name)
PACKINGS = [
    (f"import zlib, base64\nexec(zlib.decompress(base64.b64decode('{B64}')))",
     "exec of computed text (from zlib.decompress, base64.b64decode)"),
    (f"import zlib as z, base64 as b\neval(compile(z.decompress(b.b64decode('{B64}')), "
     f"'x', 'exec'))", "eval of computed text"),
    (f"exec(bytes.fromhex('{ANSWER.encode().hex()}').decode())", "exec of computed text"),
    (f"import marshal\nexec(marshal.loads({marshal.dumps(compile(ANSWER, 'a', 'exec'))!r}))",
     "marshal.loads"),
    (f"import pickle\nf = pickle.loads({pickle.dumps(len)!r})", "pickle.loads"),
    ("import builtins\ngetattr(builtins, 'ex' + 'ec')(s)", "getattr on the builtins"),
    ("getattr(__builtins__, ''.join(map(chr, [101, 120, 101, 99])))(s)",
     "getattr on the builtins"),
    ("__builtins__.__dict__['exec'](s)", "__builtins__"),
    ("run = exec\nrun(s)", "exec used as a value"),
    ("from builtins import exec as run\nrun(s)", "import builtins.exec"),
    ("m = __import__('zl' + 'ib')", "__import__"),
    ("import importlib\nm = importlib.import_module(name)", "importlib.import_module"),
    ("import types\nf = types.FunctionType(code, {})", "types.FunctionType"),
    (f"import codecs\nexec(codecs.decode({codecs.encode(ANSWER, 'rot13')!r}, 'rot13'))",
     "codecs"),
    (f"import bz2\nexec(bz2.decompress({bz2.compress(ANSWER.encode())!r}))", "exec of computed"),
    ("get_ipython().run_cell(text)", "IPython run_cell of computed text"),
    ("get_ipython().run_cell_magic('time', '', text)", "IPython run_cell_magic"),
    ("globals()['exec'](s)", "globals()[...]"),
    ("import sys\nf = getattr(sys.modules['builtins'], name)", "getattr on"),
    ("data = np.load('a.npy', allow_pickle=True)", "allow_pickle"),
    ("import ctypes\nctypes.pythonapi.PyRun_SimpleString(b'x = 1')", "ctypes.pythonapi"),
    ("f = lambda: 0\nf.__code__ = f.__code__.replace(co_code=data)", "__code__"),
    ("import subprocess\nsubprocess.run([sys.executable, '-c', text])", "subprocess.run"),
    ("import os\nos.system('python -c ' + text)", "os.system"),
    # the builtins reached through a module: each graded a copied filter 10 / 10 with no
    # finding (bwrap, warm boxes), the report saying "0 with hidden code"
    ("import sys\nsys.modules['builtins'].exec(s[::-1])", "exec of computed text"),
    ("import sys\nsys.modules['builtins'].__dict__['ex' + 'ec'](s)", "the builtins[...]"),
    ("import numpy as np\nnp.__builtins__['exec'](s[::-1])", "numpy.__builtins__ used"),
    ("import numpy as np\nnp.__builtins__['ex' + 'ec'](s)", "the builtins[...]"),
]


def scan(code: str) -> list[str]:
    return hidden.scan([("cell 3", ast.parse(code))])


@pytest.mark.parametrize("code,named", PACKINGS, ids=[n for _, n in PACKINGS])
def test_each_packing_is_named_with_its_cell(code, named):
    found = scan(code)
    assert any(f.startswith("cell 3: ") and named in f for f in found), found


def test_a_written_file_decoded_before_it_runs_is_named():
    text = "# -*- coding: unicode_escape -*-\n#\\ndef kalman_filter(z): return z\n"
    found = hidden.scan([], [("kalman_filter.py", text)])
    assert found and "unicode_escape" in found[0] and found[0].startswith("file kalman_filter.py")
    assert hidden.scan([], [("a.py", "# -*- coding: utf-8 -*-\nx = 1\n")]) == []


@pytest.mark.parametrize("code", [
    "exec('x = 1')", "eval('1 + 2')", "exec(compile('x = 1', 'f', 'exec'))",
    "get_ipython().run_line_magic('time', 'x = f(1)')",
    "get_ipython().run_cell_magic('writefile', 'kalman_filter.py', 'import numpy')",
    "get_ipython().system('pip install filterpy')", "import re\np = re.compile(pattern)",
    "import pickle\npickle.dump(results, f)", "v = getattr(model, name)", "code = 3\ncode.real",
    "x = np.linalg.eig(P)[i]", "s = text.decode('utf-8')",
])
def test_what_an_honest_notebook_writes_is_not_hidden(code):
    assert scan(code) == []


def test_no_false_flag_on_generated_honest_answers():
    rng = np.random.default_rng(5)
    for _ in range(100):
        for g in sc.GENERATORS.values():
            assert scan(g(rng)) == []


def test_findings_are_bounded():
    code = "\n".join(f"exec(s{i})" for i in range(100))
    assert len(scan(code)) == 1  # one kind, one finding
    many = "\n".join(f"exec(s{i})\nm{i} = __import__(n{i})" for i in range(100))
    assert len(hidden.scan([(f"cell {i}", ast.parse(many)) for i in range(30)])) == \
        hidden.MAX_FINDINGS


LOADER = ("import importlib.util\n"
          "def load(path):\n"
          "    spec = importlib.util.spec_from_file_location(path.stem, path)\n"
          "    module = importlib.util.module_from_spec(spec)\n"
          "    spec.loader.exec_module(module)\n"
          "    return module.kalman_filter\n")


def test_a_file_the_notebook_writes_may_be_loaded_by_its_path():
    """Lesson 08's loader of a filter file: shown code when the notebook writes the file with
    %%writefile; hidden when it loads a file it does not write, or writes one from decoded
    data."""
    written = [("kalman_filter.py", "def kalman_filter(z):\n    return z\n")]
    tree = ast.parse(LOADER)
    assert hidden.scan([("cell 2", tree)], written) == []
    assert hidden.scan([("cell 2", tree)]) == [
        "cell 2: spec_from_file_location of a Python file the notebook does not write with "
        "%%writefile"]
    literal = ast.parse("import importlib.util\n"
                        "s = importlib.util.spec_from_file_location('m', 'other.py')")
    assert hidden.scan([("cell 2", literal)], written)
    write = ast.parse(f"import zlib, base64\nopen('m.py', 'w').write(zlib.decompress("
                      f"base64.b64decode('{B64}')).decode())")
    assert any("write of decoded data to a file" in f
               for f in hidden.scan([("cell 3", write)], written))


def test_no_false_flag_on_the_packaged_masters():
    from gpsaccel.assignments import answercode, published
    from gpsaccel.assignments.homework import packaged_masters

    for master in sorted(packaged_masters().glob("*/*.ipynb")):
        sources = [s for _, s in published._cells(master)]
        places = [(f"cell {i}", ast.parse(published._python(s))) for i, s in enumerate(sources)]
        files = list(answercode.written_files(sources).items())
        assert hidden.scan(places, files) == [], master
