#!/usr/bin/env python3
"""The DDS domain through the real `hil` binary: --dds-domain, else $HIL_DDS_DOMAIN, else
$ROS_DOMAIN_ID; a bad value is a usage error (exit 2) naming its variable, and a variable that is
not used is not read. `hil replay --speed 0` publishes the shipped run on the host-only profile."""
import os
import subprocess
import sys
import unittest

HIL, SRC = sys.argv[1], sys.argv[2]
RUN = os.path.join(SRC, "examples", "runs", "press_slide")
DOMAIN = str(10 + os.getpid() % 40)


def replay(*global_args, **env):
    e = {k: v for k, v in os.environ.items() if k not in ("HIL_DDS_DOMAIN", "ROS_DOMAIN_ID")}
    e.update(env)
    return subprocess.run([HIL, *global_args, "replay", RUN, "--speed", "0"], capture_output=True, text=True, timeout=120, env=e)


class Domain(unittest.TestCase):
    def test_bad_ros_domain_id_is_named(self):
        r = replay(ROS_DOMAIN_ID="abc")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("$ROS_DOMAIN_ID", r.stderr)
        self.assertIn("'abc'", r.stderr)
        self.assertIn("0..232", r.stderr)

    def test_bad_hil_dds_domain_is_named(self):
        r = replay(HIL_DDS_DOMAIN="233", ROS_DOMAIN_ID=DOMAIN)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("$HIL_DDS_DOMAIN", r.stderr)
        self.assertNotIn("ROS_DOMAIN_ID", r.stderr)

    def test_hils_variable_wins_and_the_other_is_not_read(self):
        r = replay(HIL_DDS_DOMAIN=DOMAIN, ROS_DOMAIN_ID="abc")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("samples published", r.stderr)

    def test_command_line_wins(self):
        r = replay("--dds-domain", DOMAIN, HIL_DDS_DOMAIN="abc", ROS_DOMAIN_ID="abc")
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_ros_domain_id_alone(self):
        r = replay(ROS_DOMAIN_ID=DOMAIN)
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_help_names_both_variables(self):
        r = subprocess.run([HIL, "--help"], capture_output=True, text=True, timeout=60)
        self.assertIn("ROS_DOMAIN_ID", r.stdout)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
