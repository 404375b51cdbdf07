"""The README and docs/ as a user reads them: every link leads to a file (and heading) that
is there, the README's quick-start commands run as written on volumes made here, and every
command and flag the offline CLI's page names is one the CLI has.

Usage: /usr/bin/python3 docs_test.py PIPELINE_BIN REPOSITORY_ROOT"""
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile
import unittest

import numpy as np

PIPELINE = ROOT = None


def slug(heading):
    """The anchor a Markdown renderer gives a heading."""
    s = heading.strip().lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def pages():
    return [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


def fenced(text, lang):
    return re.findall(r"^```%s\n(.*?)^```" % lang, text, flags=re.S | re.M)


class DocsTest(unittest.TestCase):
    def test_every_link_leads_to_a_file_and_heading_that_are_there(self):
        for page in pages():
            text = page.read_text()
            for target in re.findall(r"\]\(([^)\s]+)\)", text):
                if re.match(r"[a-z]+://", target):
                    continue
                path, _, anchor = target.partition("#")
                dest = (page.parent / path).resolve() if path else page
                self.assertTrue(dest.exists(), "%s links to %s, which is not there" % (page.name, target))
                if anchor and dest.suffix == ".md":
                    heads = {slug(h) for h in re.findall(r"^#+ (.*)$", dest.read_text(), flags=re.M)}
                    self.assertIn(anchor, heads, "%s links to %s: no such heading" % (page.name, target))

    def test_every_docs_page_is_linked_from_the_readme(self):
        readme = (ROOT / "README.md").read_text()
        for page in sorted((ROOT / "docs").glob("*.md")):
            self.assertIn("docs/" + page.name, readme, "README does not link %s" % page.name)

    def test_the_readme_is_at_most_300_lines(self):
        self.assertLessEqual(len((ROOT / "README.md").read_text().splitlines()), 300)

    def test_the_readmes_quick_start_runs_as_written(self):
        """Each `$P` line of the README's sh blocks, its file names swapped for volumes made
        here (a segmented phantom, a grey scan with a known sheet), its [optional] parts
        taken as given; `phantom` lines run too."""
        readme = (ROOT / "README.md").read_text()
        lines = [l for block in fenced(readme, "sh") for l in block.splitlines() if l.startswith("$P ")]
        self.assertGreaterEqual(len(lines), 6, lines)
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            scan = tmp / "scan_64x56x48_u8.raw"
            subprocess.run([PIPELINE, "phantom", "--preset=sample", "--dims=64x56x48", "-o", str(scan)],
                           check=True, capture_output=True)
            grey = tmp / "ct_64x64x48_u16.raw"
            z = np.arange(48)[:, None, None]
            y = np.arange(64)[None, :, None]
            depth = np.abs(z - 20 - 0.3 * y)  # a sheet 2 voxels open, tilted
            open_share = np.clip(1.5 - depth, 0, 1) * np.ones((1, 64, 64))
            rng = np.random.default_rng(1)
            values = 30000 - 20000 * open_share + rng.normal(0, 400, open_share.shape)
            values.astype("<u2").tofile(grey)
            for line in lines:
                line = line.split("  #")[0].strip()
                line = re.sub(r"\[([^\]]*)\]", r"\1", line)  # optional parts, as given
                line = line.replace("VOID,ROCK", "10000,30000")
                args = shlex.split(line)[1:]
                args = [str(scan) if a == "my_scan.tif" else str(grey) if a == "ct_512x512x400_u16.raw"
                        else str(tmp / a) if a.endswith("_u8.raw") or a == "out" else a for a in args]
                with self.subTest(line=line):
                    r = subprocess.run([PIPELINE] + args, cwd=tmp, capture_output=True, text=True,
                                       timeout=600)
                    self.assertEqual(r.returncode, 0, "%s\n%s" % (line, r.stderr[-2000:]))

    def test_the_cli_pages_commands_and_flags_are_the_clis(self):
        text = (ROOT / "docs" / "cli.md").read_text()
        lines = [l for block in fenced(text, "sh") for l in block.splitlines() if l.startswith("$P ")]
        self.assertGreaterEqual(len(lines), 8, lines)
        table = subprocess.run([PIPELINE, "params", "--markdown"], capture_output=True, text=True,
                               check=True).stdout
        parameters = set(re.findall(r"`--([a-z_0-9]+)`", table))
        self.assertGreater(len(parameters), 50)
        for line in lines:
            command = line.split()[1]
            r = subprocess.run([PIPELINE, command, "--helpfull"], capture_output=True, text=True)
            own = set(re.findall(r"--([a-z_0-9]+)", r.stdout + r.stderr))
            self.assertTrue(own, "%s --helpfull lists no flag" % command)
            known = own | parameters
            for flag in re.findall(r"--([a-z_0-9]+)", line.split("  #")[0]):
                self.assertIn(flag, known, "docs/cli.md: `%s` has no flag --%s" % (command, flag))


if __name__ == "__main__":
    PIPELINE, ROOT = sys.argv[1], pathlib.Path(sys.argv[2]).resolve()
    del sys.argv[1:3]
    unittest.main(verbosity=2)
