"""Pythonic errors (docs/python.md, "Errors"): each kind of failure is caught by the builtin exception
a Python user reaches for and by raypc.Error; messages name Python's arguments, where the CLI's
name its flags; a failed raypc.open leaves nothing behind; closing one view of a shared server
leaves the others working, and closing the last frees the port."""
import socket
import subprocess
import threading
import urllib.parse

import pytest

import raypc
from conftest import CONTEST_LAYOUT, RAYPC_EXE, run_cli


def raised(call, builtin):
    """Calls `call`, which must fail with `builtin`; returns the exception after checking it is a
    raypc.Error (a ValueError) too."""
    with pytest.raises(builtin) as caught:
        call()
    assert isinstance(caught.value, raypc.Error) and isinstance(caught.value, ValueError)
    return caught.value


def check_python_message(error, *parts):
    text = str(error)
    for part in parts:
        assert part in text
    assert "--" not in text, text  # no CLI flag


def test_the_classes_are_the_builtin_ones():
    assert issubclass(raypc.Error, ValueError)
    for kind, builtin in [(raypc.NotFoundError, FileNotFoundError), (raypc.UnknownNameError, KeyError),
                          (raypc.OutOfRangeError, IndexError)]:
        assert issubclass(kind, raypc.Error) and issubclass(kind, builtin)
    # Each kind is only the one builtin: an IndexError handler does not catch an unknown name.
    assert not issubclass(raypc.UnknownNameError, IndexError)
    assert not issubclass(raypc.OutOfRangeError, KeyError)
    assert not issubclass(raypc.NotFoundError, LookupError)


def test_missing_files_and_datasets_are_file_not_found(tmp_path):
    e = raised(lambda: raypc.open(tmp_path / "missing.nc", progress=False), FileNotFoundError)
    check_python_message(e, "missing.nc: no such file")
    e = raised(lambda: raypc.Dataset(tmp_path / "nowhere"), FileNotFoundError)
    check_python_message(e, "nowhere: not a directory")
    (tmp_path / "empty").mkdir()
    e = raised(lambda: raypc.Dataset(tmp_path / "empty"), raypc.NotFoundError)
    check_python_message(e, "no dataset.json")
    e = raised(lambda: raypc.State(tmp_path / "missing.json"), FileNotFoundError)
    check_python_message(e, "missing.json: cannot read the state")
    # A file where a dataset directory belongs is there: a wrong argument, not a missing one.
    with pytest.raises(raypc.Error) as caught:
        raypc.Dataset(sorted(CONTEST_LAYOUT.glob("*.nc"))[0])
    assert not isinstance(caught.value, FileNotFoundError)


def test_unknown_names_are_key_errors_that_print_plainly(contest):
    e = raised(lambda: contest.field("pressure"), KeyError)
    assert str(e).startswith("variable: unknown variable 'pressure'; the dataset has: temperature")  # not quoted
    e = raised(lambda: contest.probe(0, 0, 5000, variable="pressure"), KeyError)
    check_python_message(e, "variable: unknown variable 'pressure'")
    e = raised(lambda: contest.stats(by="depth", mean_of="pressure", progress=False), raypc.UnknownNameError)
    check_python_message(e, "mean_of: unknown variable 'pressure'")
    e = raised(lambda: contest.stats({"brushes": [{"name": "pressure", "min": 0, "max": 1}]}, progress=False),
               KeyError)
    check_python_message(e, "brushes[0] (pressure): unknown variable or coordinate 'pressure'")
    e = raised(lambda: contest.render({"color": {"variable": "pressure"}}, size=(32, 32), progress=False), KeyError)
    check_python_message(e, "variable 'pressure' is unknown")
    e = raised(lambda: contest.to_xarray(0, variables=["temperature", "pressure"]), KeyError)
    check_python_message(e, "'pressure'")


def test_steps_and_levels_out_of_range_are_index_errors(contest):
    e = raised(lambda: contest.field("temperature", 7), IndexError)
    assert str(e) == "step: 7 out of range 0..2"
    e = raised(lambda: contest.field("temperature", 0, level=9), IndexError)
    assert str(e) == "level: 9 out of range 0..2"
    e = raised(lambda: contest.field("temperature", -1), IndexError)
    assert str(e) == "step: -1 out of range 0..2"
    e = raised(lambda: contest.probe(0, 0, 5000, step="3Myr"), IndexError)
    check_python_message(e, "step: no step at 3 Myr")
    e = raised(lambda: contest.probe(0, 0, 5000, level=5), raypc.OutOfRangeError)
    assert str(e) == "level: 5 out of range 0..2"
    e = raised(lambda: contest.sample(5), IndexError)
    assert str(e) == "step: 5 out of range 0..2"  # the argument, not the dataset's directory
    e = raised(lambda: contest.stats(steps=(0, 9), progress=False), IndexError)
    assert str(e) == "steps: 9 out of range 0..2"


def test_wrong_types_are_type_errors(contest):
    for step in (1.5, [1], None, True):
        with pytest.raises(TypeError, match=f"step: expected a step index .* not {type(step).__name__}"):
            contest.field("temperature", step)
    with pytest.raises(TypeError, match="window: expected a number of steps"):
        contest.pathlines(0, window=2.5)
    with pytest.raises(TypeError, match="steps: expected None, a step, a .first, last. pair or a range"):
        contest.stats(steps=(0, 1, 2), progress=False)
    with pytest.raises(TypeError):  # the compiled module's own check of an int argument
        contest.field("temperature", 0, level=0.5)
    with pytest.raises(TypeError):
        contest.field(3)
    # A NumPy integer is a step like an int.
    import numpy as np

    assert contest.field("temperature", np.int64(2)).step == 2


def test_bad_values_are_value_errors_naming_the_python_argument(contest, tmp_path):
    e = raised(lambda: contest.probe(95, 0, 5000), ValueError)
    assert not isinstance(e, (KeyError, IndexError, FileNotFoundError))
    assert str(e) == "lat: 95 is outside [-90, 90] degrees"
    e = raised(lambda: contest.probe(0, 0, 3000), ValueError)
    check_python_message(e, "r_km: 3000 km is outside the mantle shell")
    e = raised(lambda: contest.field("temperature", "abc"), ValueError)
    check_python_message(e, "step: 'abc' is neither a step index nor a time like 24Myr")
    files = sorted(CONTEST_LAYOUT.glob("spherical*.nc"))
    # raypc.open's keywords become the CLI's options; their messages name the keywords again.
    e = raised(lambda: raypc.open(*files, dataset=tmp_path / "x", time_units="days", progress=False), ValueError)
    check_python_message(e, "time_units 'days'")
    e = raised(lambda: raypc.open(*files, dataset=tmp_path / "x", dt_myr=-1, progress=False), ValueError)
    check_python_message(e, "dt_myr: -1 is not a positive time step")
    e = raised(lambda: raypc.open(*files, dataset=tmp_path / "x", no_such_option=3, progress=False), ValueError)
    check_python_message(e, "no_such_option")
    e = raised(lambda: raypc.open(*files, dataset=tmp_path / "x", pathline_field="pressure", progress=False),
               KeyError)
    check_python_message(e, "pathline_field: no variable 'pressure'")
    assert not (tmp_path / "x").exists()


def test_the_cli_keeps_its_flags_in_the_same_messages(contest):
    for changed, message in [({"--lat": 95}, "--lat: 95 is outside [-90, 90] degrees"),
                             ({"--r": 3000}, "--r: 3000 km is outside the mantle shell"),
                             ({"--var": "pressure"}, "--var: unknown variable 'pressure'"),
                             ({"--time": 7}, "--time: 7 out of range 0..2"),
                             ({"--lod": 9}, "--lod: 9 out of range 0..2")]:
        options = {"--lat": 0, "--lon": 0, "--r": 5000, **changed}
        result = run_cli("probe", contest.path, *[x for item in options.items() for x in item], check=False)
        assert result.returncode != 0 and message in result.stderr, (changed, result.stderr)


def not_netcdf(tmp_path):
    bad = tmp_path / "in" / "x.nc"
    bad.parent.mkdir()
    bad.write_text("this is not a netCDF file\n")
    return bad


def test_a_failed_open_leaves_no_directory(tmp_path):
    bad = not_netcdf(tmp_path)
    e = raised(lambda: raypc.open(bad, progress=False), ValueError)
    check_python_message(e, "x.nc: not a netCDF file")
    assert sorted(p.name for p in bad.parent.iterdir()) == ["x.nc"]  # no x.raypc beside it
    # Directories the run created for dataset= go, parents included; what existed stays.
    raised(lambda: raypc.open(bad, dataset=tmp_path / "new" / "a" / "b", progress=False), ValueError)
    assert not (tmp_path / "new").exists()
    (tmp_path / "existing").mkdir()
    raised(lambda: raypc.open(bad, dataset=tmp_path / "existing" / "ds", progress=False), ValueError)
    assert (tmp_path / "existing").is_dir() and not any((tmp_path / "existing").iterdir())
    raised(lambda: raypc.open(bad, dataset=tmp_path / "existing", progress=False), ValueError)
    assert (tmp_path / "existing").is_dir()
    # A directory that holds something is never removed, even one this run would have created
    # (here the user's file, put there as if by another process).
    (tmp_path / "kept").mkdir()
    (tmp_path / "kept" / "note.txt").write_text("mine")
    raised(lambda: raypc.open(bad, dataset=tmp_path / "kept", progress=False), ValueError)
    assert (tmp_path / "kept" / "note.txt").read_text() == "mine"


def test_failed_cli_runs_of_files_leave_no_directory(tmp_path):
    bad = not_netcdf(tmp_path)
    for command in (["preprocess", bad, "-o", tmp_path / "out"], ["render", bad, "-o", tmp_path / "x.png"],
                    ["serve", bad, "--port", "0"]):
        result = subprocess.run([RAYPC_EXE, *map(str, command)], capture_output=True, text=True, timeout=120)
        assert result.returncode != 0 and "x.nc: not a netCDF file" in result.stderr, (command, result.stderr)
        assert sorted(p.name for p in bad.parent.iterdir()) == ["x.nc"], command
        assert not (tmp_path / "out").exists() and not (tmp_path / "x.png").exists()


def port_of(view):
    return urllib.parse.urlsplit(view.url).port


def test_closing_one_view_keeps_the_shared_server_and_the_last_frees_the_port(contest):
    first = raypc.show(contest)
    second = raypc.show(contest)
    try:
        assert second._server is first._server and second.url == first.url  # one server, shared
        first.close()
        first.close()  # again: nothing more
        assert second.link()["version"] >= 0  # still served, at once (no timeout)
        with pytest.raises(raypc.Error, match="this view is closed"):
            first.link()
        third = raypc.show(contest)  # a new view of the running server
        assert third._server is second._server
        third.close()
        assert second.link()["sessions"] == 0
    finally:
        second.close()
    with pytest.raises(ConnectionRefusedError):
        socket.create_connection(("127.0.0.1", port_of(first)), timeout=5).close()
    # Showing the dataset again starts a new server.
    again = raypc.show(contest)
    try:
        assert again.link()["version"] == 0
    finally:
        again.close()


def test_a_server_that_does_not_answer_is_a_raypc_error_naming_the_url():
    # A socket that listens but never answers: the request times out.
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(1)
        url = f"http://127.0.0.1:{silent.getsockname()[1]}/"
        view = raypc.View(url)
        view.timeout = 0.5
        with pytest.raises(raypc.Error, match=r"127\.0\.0\.1:\d+/api/link: the RayPC server does not answer"):
            view.link()
        view.close()
    # Nothing listening: refused.
    view = raypc.View(url)
    with pytest.raises(raypc.Error, match=r"/api/link: the RayPC server does not answer"):
        view.link()
    # Something else listening, which answers what is not HTTP.
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen(1)

        def answer_garbage():
            connection, _ = other.accept()
            with connection:
                connection.recv(4096)
                connection.sendall(b"SSH-2.0-OpenSSH\r\n")

        thread = threading.Thread(target=answer_garbage, daemon=True)
        thread.start()
        view = raypc.View(f"http://127.0.0.1:{other.getsockname()[1]}/")
        with pytest.raises(raypc.Error, match=r"/api/link: the answer is not a RayPC server's"):
            view.link()
        thread.join(timeout=5)
