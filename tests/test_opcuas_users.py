"""The OPC UA server's user file (softplc_lite/tlm/opcuas/users.py) and
``softplc opcua-user``, which writes it."""

from __future__ import annotations

import stat

import pytest

from helpers.cli import softplc_here
from softplc_lite.tlm.opcuas.users import FILE_NAME, Users, hash_password, parse
from softplc_lite.tlm.errors import ModuleErrors

GOOD = hash_password("some long password")


def test_a_password_checks_only_against_its_own_hash():
    users = Users()
    users.set("operator", "first password", can_write=True)
    users.set("viewer", "second password", can_write=False)
    assert users.check("operator", "first password").can_write
    assert not users.check("viewer", "second password").can_write
    assert users.check("operator", "second password") is None
    assert users.check("nobody", "first password") is None
    assert users.check("operator", None) is None


def test_each_user_has_a_salt_of_its_own():
    one, two = hash_password("same password"), hash_password("same password")
    assert one.split("$")[4] != two.split("$")[4] and one != two


def test_a_saved_file_reads_back_and_is_private(tmp_path):
    users = Users()
    users.set("operator", "first password", can_write=True)
    users.set("viewer", "second password", can_write=False)
    users.save(tmp_path / FILE_NAME)
    again = Users.load(tmp_path / FILE_NAME)
    assert {n: e.can_write for n, e in again.entries.items()} == {"operator": True, "viewer": False}
    assert again.check("viewer", "second password") is not None
    assert stat.S_IMODE((tmp_path / FILE_NAME).stat().st_mode) == 0o600


def test_no_file_is_no_users(tmp_path):
    assert Users.load(tmp_path / FILE_NAME).entries == {}


def test_every_bad_line_is_reported_where_it_is():
    text = "\n".join([
        "# name rights hash",
        f"operator write {GOOD}",
        f"bad/name read {GOOD}",
        f"viewer  admin {GOOD}",
        "short read scrypt$16384$8$1$AAAA$BBBB",
        "lonely read",
        f"operator read {GOOD}  # again",
        f"extra read {GOOD} more",
        "costly read " + GOOD.replace("scrypt$16384$", "scrypt$16385$"),
    ]) + "\n"
    with pytest.raises(ModuleErrors) as caught:
        parse(text, "app/OPCUAS.USERS")
    assert caught.value.report().splitlines() == [
        "app/OPCUAS.USERS:3:1: expected a user name of 1 to 64 letters, digits, _ . @ or -, not 'bad/name'",
        "app/OPCUAS.USERS:4:9: expected rights read or write, not 'admin'",
        "app/OPCUAS.USERS:5:12: expected a salt of 8 bytes or more and a key of 32 bytes",
        "app/OPCUAS.USERS:6:12: expected three fields: name, rights (read or write), password hash",
        "app/OPCUAS.USERS:7:1: user 'operator' is named twice (first on line 2)",
        f"app/OPCUAS.USERS:8:{len('extra read ' + GOOD) + 2}: expected nothing more",
        "app/OPCUAS.USERS:9:13: expected N a power of 2 from 2 to 1048576, r from 1 to 32 and p from 1 to 16",
    ]


def test_the_command_adds_changes_and_removes_a_user_without_echo(tmp_path):
    app = tmp_path / "tank"
    app.mkdir()
    added = softplc_here("opcua-user", str(app), "operator", "--write", stdin="a long password\n")
    assert added.returncode == 0, added.stderr
    assert added.stdout == f"added operator (write) in {app / FILE_NAME}\n"
    changed = softplc_here("opcua-user", str(app), "operator", stdin="another password\n")
    assert changed.stdout == f"changed operator (read) in {app / FILE_NAME}\n"
    text = (app / FILE_NAME).read_text()
    for proc in (added, changed):
        assert "password" not in proc.stdout + proc.stderr
    assert "a long password" not in text and "another password" not in text
    users = Users.load(app / FILE_NAME)
    assert users.check("operator", "another password") is not None
    assert not users.entries["operator"].can_write
    removed = softplc_here("opcua-user", str(app), "operator", "--remove")
    assert removed.returncode == 0 and Users.load(app / FILE_NAME).entries == {}


@pytest.mark.parametrize("args,stdin,message", [
    (["bad name"], "a long password\n", "error: expected a user name of 1 to 64 letters"),
    (["operator"], "short\n", "error: expected a password of 8 characters or more"),
    (["operator"], "", "error: expected a password of 8 characters or more"),
    (["nobody", "--remove"], "", "no user 'nobody'"),
])
def test_the_command_refuses_bad_input(tmp_path, args, stdin, message):
    proc = softplc_here("opcua-user", str(tmp_path), *args, stdin=stdin)
    assert proc.returncode == 1 and message in proc.stderr
    assert not (tmp_path / FILE_NAME).exists()


def test_the_command_reports_a_bad_file_located(tmp_path):
    (tmp_path / FILE_NAME).write_text("operator sudo x\n")
    proc = softplc_here("opcua-user", str(tmp_path), "viewer", stdin="a long password\n")
    assert proc.returncode == 1
    assert f"{tmp_path / FILE_NAME}:1:10: expected rights read or write, not 'sudo'" in proc.stderr
    assert f"{tmp_path / FILE_NAME}:1:15: expected a password hash" in proc.stderr
    assert (tmp_path / FILE_NAME).read_text() == "operator sudo x\n"


def test_an_unknown_name_costs_a_derivation_as_a_known_one_does(monkeypatch):
    from softplc_lite.tlm.opcuas import users as module
    derived = []
    real = module._derive
    monkeypatch.setattr(module, "_derive", lambda *a: derived.append(a[2:]) or real(*a))
    users = Users()
    users.set("operator", "first password", can_write=True)
    derived.clear()
    users.check("operator", "wrong password")
    users.check("nobody", "wrong password")
    assert derived == [module.COST, module.COST]
