"""The Python package's import graph (tools/python_imports.py) has no cycles."""
import ast
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "tools"))
import python_imports  # noqa: E402


def test_the_package_has_no_import_cycle():
    edges = python_imports.graph()
    assert "sim4cv.driving_eval" in edges and "sim4cv.client" in edges  # the package was found
    assert python_imports.cycles(edges) == []


def write_package(root, files):
    package = root / "pkg"
    package.mkdir()
    for name, text in files.items():
        (package / name).write_text(text)
    return package


def test_a_cycle_through_a_function_local_import_is_found(tmp_path):
    package = write_package(tmp_path, {
        "__init__.py": "",
        "a.py": "from . import b\n",
        "b.py": "def f():\n    from .a import thing\n    return thing\n",
        "c.py": "from .b import f\n",
    })
    assert python_imports.cycles(python_imports.graph(package)) == [["pkg.a", "pkg.b"]]


def test_the_main_block_and_package_names_do_not_make_cycles(tmp_path):
    package = write_package(tmp_path, {
        "__init__.py": "from .a import run\n",
        "a.py": "from . import b\n\ndef run():\n    pass\n",
        "b.py": "from pkg import c\n",  # a module of the package, not its __init__
        "c.py": "if __name__ == '__main__':\n    from .a import run\n    run()\n",
    })
    edges = python_imports.graph(package)
    assert edges["pkg.b"] == {"pkg.c"} and edges["pkg.c"] == set()
    assert python_imports.cycles(edges) == []


def test_is_main_block():
    main, other = ast.parse("if __name__ == '__main__':\n    pass\nif x == '__main__':\n    pass\n").body
    assert python_imports.is_main_block(main) and not python_imports.is_main_block(other)
