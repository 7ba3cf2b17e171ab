import subprocess
import sys


def test_learning_does_not_import_the_arena_or_engine():
    code = ("import sys, confront.learning, confront.learning.migration, confront.learning.envloop; "
            "bad = [m for m in sys.modules if m.startswith(('confront.arena', 'confront.engine'))]; "
            "print(bad); sys.exit(1 if bad else 0)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
