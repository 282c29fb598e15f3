"""Every CTest name is short and the same in every build: no printed parameter bytes
(`GetParam() = 104-byte object <80-24 D8-45 ...>`), which hold heap addresses."""
import os
import re
import subprocess

MAX_NAME = 120


def test_ctest_names_are_readable_and_stable():
    listing = subprocess.run(["ctest", "-N", "--test-dir", os.environ["CORO_BUILD_DIR"]],
                             capture_output=True, text=True, check=True).stdout
    names = re.findall(r"^\s*Test\s+#\d+: (.*)$", listing, re.MULTILINE)
    assert len(names) > 100, listing[:2000]
    bad = [n for n in names if "GetParam" in n or "object <" in n or "#" in n or len(n) > MAX_NAME]
    assert bad == [], "\n".join(bad[:20])
