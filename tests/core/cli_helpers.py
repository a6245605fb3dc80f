"""Running ``amra`` in-process from the tests (pytest puts this directory on sys.path)."""
import json

from amra_core.cli import main


def strict_json(text: str):
    """Parse JSON, refusing the non-standard NaN/Infinity tokens Python would otherwise accept."""
    def bad(tok):
        raise ValueError(f"non-standard JSON constant {tok}")
    return json.loads(text, parse_constant=bad)


def run_cli(capsys, *argv):
    """``amra *argv`` in-process: (exit code, stdout, stderr). argparse errors exit via SystemExit."""
    try:
        rc = main(list(argv))
    except SystemExit as exc:
        rc = exc.code
    out, err = capsys.readouterr()
    return rc, out, err
