"""The `sim4cv` command (sim4cv/cli.py): every command reaches its module's command line,
--help works everywhere with status 0, usage errors are status 2 with a message, and the
daemon is found without $SIM4CVD when sim4cv is installed (daemon.installed_daemon)."""

import os
import stat

import pytest

import conftest  # noqa: F401  (puts clients/python on sys.path)
from sim4cv import cli, daemon


@pytest.mark.parametrize("command", sorted(cli.COMMANDS))
def test_every_command_has_help(command, capsys):
    assert cli.main([command, "--help"]) == 0
    assert "python3 -m sim4cv.%s" % cli.COMMANDS[command][0].split("_cli")[0] in capsys.readouterr().out


def test_help_lists_every_command(capsys):
    assert cli.main(["--help"]) == 0
    out = capsys.readouterr().out
    for command in cli.COMMANDS:
        assert "\n  %s " % command in out


def test_no_command_and_unknown_command_are_usage_errors(capsys):
    assert cli.main([]) == 2
    assert "usage: sim4cv COMMAND" in capsys.readouterr().err
    assert cli.main(["tracks"]) == 2
    assert "sim4cv: unknown command 'tracks'" in capsys.readouterr().err


def test_a_bad_option_of_a_command_is_a_usage_error(capsys):
    assert cli.main(["sequences", "generate"]) == 2
    assert "generate: error: the following arguments are required: --out" in capsys.readouterr().err


def test_a_subcommand_added_to_a_module_is_reached_without_editing_cli(monkeypatch, capsys):
    import sim4cv.sequences_cli as sequences_cli
    seen = []
    monkeypatch.setattr(sequences_cli, "main", lambda argv: seen.append(argv) or 0)
    assert cli.main(["sequences", "new-subcommand", "--x", "1"]) == 0
    assert seen == [["new-subcommand", "--x", "1"]]


def test_installed_daemon_is_found_on_path_without_sim4cvd(tmp_path, monkeypatch):
    fake_bin = tmp_path / "bin"
    fake_bin.mkdir()
    binary = fake_bin / "sim4cvd"
    binary.write_text("#!/bin/sh\n")
    binary.chmod(binary.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("PATH", str(fake_bin) + os.pathsep + os.environ.get("PATH", ""))
    monkeypatch.delenv("SIM4CVD", raising=False)
    assert daemon.installed_daemon() == str(binary)
    monkeypatch.setattr(daemon, "IN_SOURCE_TREE", False)
    assert daemon.daemon_path() == str(binary)


def test_without_any_daemon_the_error_says_how_to_install(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("SIM4CVD", raising=False)
    monkeypatch.setattr(daemon, "IN_SOURCE_TREE", False)
    monkeypatch.setattr(daemon.sys, "prefix", str(tmp_path))
    monkeypatch.setattr(daemon.os, "access", lambda path, mode: False)
    with pytest.raises(daemon.DaemonError, match=r"sim4cvd not found on PATH .* install sim4cv"):
        daemon.daemon_path()
