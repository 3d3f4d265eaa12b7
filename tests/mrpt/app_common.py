"""What every app test shares: the runner of the unmodified MRPT apps (the plugin and the seed shim
preloaded), the datasets' names and the failure report."""
import glob
import os
import re
import shutil
import subprocess
import sys
import time

SENA = "2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog"


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


class Runner:
    def __init__(self, a):
        self.a = a

    def config(self, name, run_dir):
        """Copies a config into run_dir with the dataset directory substituted."""
        with open(os.path.join(self.a.config_dir, name)) as f:
            text = f.read()
        text = text.replace("/usr/share/mrpt/datasets", self.a.datasets)
        dst = os.path.join(run_dir, name)
        with open(dst, "w") as f:
            f.write(text)
        return dst

    def run_dir(self, name):
        d = os.path.join(self.a.work_dir, name)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        return d

    def app(self, args, cwd, preload=True, timeout=280, seed=1):
        """Runs an unmodified MRPT app; the seed shim pins MRPT's clock-seeded generator. With the
        plugin (`preload`), through the rtog-mrpt launcher, as a user runs it: it preloads the plugin
        after what LD_PRELOAD holds (the sanitizer runtime first, the seed shim)."""
        env = dict(os.environ)
        env["LD_PRELOAD"] = " ".join(self.a.preload_first + [self.a.seed_shim])
        if preload:
            args = [self.a.launcher] + list(args)
        env["RTOG_TEST_SEED"] = str(seed)
        env.pop("DISPLAY", None)
        t0 = time.time()
        p = subprocess.run(args, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, timeout=timeout)
        out = p.stdout.decode(errors="replace")
        with open(os.path.join(cwd, os.path.basename(args[1] if preload else args[0]) + ".log"), "a") as f:
            f.write(out)
        print("$ RTOG_TEST_SEED=%d %s  -> exit %d in %.1f s" % (seed,
                                                                " ".join(args), p.returncode, time.time() - t0))
        return p.returncode, out

    def run_config(self, run_name, cfg_name, app, args=(), preload=True, seed=1, subdirs=()):
        """Fresh run directory, config copied in, `app cfg args...` run there; fails on a non-zero
        exit. Returns (run directory, output)."""
        d = self.run_dir(run_name)
        cfg = self.config(cfg_name, d)
        for sub in subdirs:
            os.makedirs(os.path.join(d, sub))
        rc, out = self.app([app, cfg] + list(args), d, preload=preload, seed=seed)
        if rc != 0:
            fail("%s (%s) exited %d:\n%s" % (app, cfg_name, rc, out[-3000:]))
        return d, out

    def mapcheck(self, path, min_occupied):
        p = subprocess.run([self.a.mapcheck, path, "--min-occupied", str(min_occupied)], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT)
        out = p.stdout.decode()
        print("mapcheck %s:\n%s" % (os.path.basename(path), out.strip()))
        if p.returncode != 0:
            fail("map %s does not load back or is unsound" % path)
        return dict(l.split(" ", 1) for l in out.strip().splitlines())

    def one_file(self, pattern):
        files = glob.glob(pattern)
        if len(files) != 1:
            fail("expected one file matching %s, found %s" % (pattern, files))
        return files[0]


PDF_RE = re.compile(r"PDF estimation: \(([-\d.]+),([-\d.]+),([-\d.]+)deg\)")
