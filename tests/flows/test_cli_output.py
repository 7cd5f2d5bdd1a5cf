"""What a run prints last: the Prefect link, then where the UI's login string is."""

from flows.cli_output import AUTH_STRING_FILE, with_record_access

TEXT = "7 points (7 cached, 0 computed) in 3.0 s\nPrefect flow run: http://127.0.0.1:4200/runs/x"


def test_the_login_string_file_follows_the_prefect_link():
    summary = {"flow_run_url": "http://127.0.0.1:4200/runs/x", AUTH_STRING_FILE: "/s/auth-string"}
    lines = with_record_access(TEXT, summary).splitlines()
    assert lines[:-1] == TEXT.splitlines()
    assert lines[-1] == (
        "The Prefect UI asks once per browser for its auth string: paste the content of "
        "/s/auth-string (eskin server status names it too)."
    )


def test_nothing_is_added_without_a_flow_run_or_a_local_server():
    # A server named by PREFECT_API_URL is the user's own: its login is theirs to know.
    assert with_record_access(TEXT, {"flow_run_url": "http://h/runs/x"}) == TEXT
    assert with_record_access("done", {AUTH_STRING_FILE: "/s/auth-string"}) == "done"
