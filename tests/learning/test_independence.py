import subprocess
import sys


def test_learning_does_not_import_the_arena_or_engine():
    """Neither the learners nor the migration experiment built on them (paper section 6.2) need a battle."""
    code = ("import sys, confront.learning, confront.learning.envloop, confront.experiments.migration; "
            "bad = [m for m in sys.modules if m.startswith(('confront.arena', 'confront.engine'))]; "
            "print(bad); sys.exit(1 if bad else 0)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
