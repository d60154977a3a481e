#!/usr/bin/env python3
"""DDS Security through the real `hil` binary (docs/security.md): a keystore made by `hil keystore`,
two authorised processes exchanging the shipped run, encrypted on the wire, and what is refused:
a participant without a certificate, one whose certificate is from another CA, one whose
permissions name other topics, and a tampered permissions file.

Usage: test_security.py HIL SOURCE_DIR [TestClass ...]. Each class uses its own DDS domain (36-41)
so ctest can run them in parallel; all traffic stays on 127.0.0.1."""
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import unittest

HIL, SRC = sys.argv[1], sys.argv[2]
RUN = os.path.join(SRC, "examples", "runs", "press_slide")
N = sum(1 for _ in open(os.path.join(RUN, "samples.csv"))) - 1  # samples in the run
UDP_PROFILE = os.path.join(SRC, "tests", "security", "dds_udp_loopback.xml")


def clean_env():
    return {k: v for k, v in os.environ.items() if k not in ("HIL_DDS_DOMAIN", "ROS_DOMAIN_ID", "HIL_DDS_PROFILE")}


def hil(*args, timeout=120):
    return subprocess.run([HIL, *args], capture_output=True, text=True, timeout=timeout, env=clean_env())


def start(*args):
    return subprocess.Popen([HIL, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=clean_env())


def finish(p, timeout=60):
    out, err = p.communicate(timeout=timeout)
    return p.returncode, out, err


# An outsider listens until the test stops it, not for a fixed time: under load (ctest -j2 on two
# cores) the authorised pair's handshake alone can take longer than any window fixed in advance, and
# a listener that gave up early would prove nothing. `hil echo` ends cleanly on SIGTERM.
LISTEN_S = "120"  # only a bound should the test itself hang


def stop(p, settle_s=1.0):
    """Stops a listener still running after the replays ended, once late samples had time to arrive."""
    time.sleep(settle_s)
    p.terminate()
    return finish(p)


def samples(echo_stdout):
    """Sample indices `hil echo pose_wrench` printed (Fast DDS's own log lines are skipped)."""
    return [int(line.split()[0][1:]) for line in echo_stdout.splitlines() if line.startswith("#")]


class Keystore:
    """A keystore in a temporary directory: `replay` may publish pose_wrench, `echo` subscribe to it,
    `other` only use device_status."""

    def __init__(self, test):
        self.dir = tempfile.mkdtemp(prefix="hil-ks-")
        test.addCleanup(shutil.rmtree, self.dir, True)
        for args in (["create", self.dir, "--days", "2"],
                     ["add", self.dir, "replay", "--publish", "/hil/pose_wrench"],
                     ["add", self.dir, "echo", "--subscribe", "rt/hil/pose_wrench"],
                     ["add", self.dir, "other", "--publish", "/hil/device_status", "--subscribe", "/hil/device_status"]):
            r = hil("keystore", *args)
            test.assertEqual(r.returncode, 0, r.stderr)

    def secure(self, name):
        return ["--secure", f"{self.dir}:{name}"]


class Exchange(unittest.TestCase):
    DOMAIN = "36"

    def exchange(self, echo_args, replay_args):
        echo = start("--dds-domain", self.DOMAIN, *echo_args, "echo", "pose_wrench", "-n", str(N), "--timeout", "60")
        time.sleep(0.3)
        replay = hil("--dds-domain", self.DOMAIN, *replay_args, "replay", RUN, "--speed", "0", "--wait-subscribers", "1",
                     "--wait-timeout", "60")
        rc, out, err = finish(echo)
        self.assertEqual(replay.returncode, 0, replay.stderr)
        self.assertEqual(rc, 0, err)
        self.assertEqual(samples(out), list(range(N)))

    def test_two_authorised_participants_get_every_sample(self):
        ks = Keystore(self)
        # replay's identity is its role: participants/replay.
        self.exchange(ks.secure("echo"), ["--secure", ks.dir])

    def test_the_secure_profile_example_with_a_keystore(self):
        ks = Keystore(self)
        with open(os.path.join(SRC, "idl", "profiles", "dds_secure.xml")) as f:
            xml = f.read()
        xml = xml.replace("file:///etc/hil/keystore", "file://" + ks.dir).replace("participants/acquire/", "participants/replay/")
        profile = os.path.join(ks.dir, "secure_profile.xml")
        with open(profile, "w") as f:
            f.write(xml)
        self.exchange(ks.secure("echo"), ["--dds-profile", profile, "--dds-profile-name", "hil_secure"])


class Capture(unittest.TestCase):
    """The same exchange over UDPv4 on 127.0.0.1 only (no shared memory), captured on lo."""
    DOMAIN = 37

    def capture(self, ks_echo, ks_replay):
        base = 7400 + 250 * self.DOMAIN  # this domain's RTPS ports: base .. base + 249
        sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(0x0003))
        # A large receive buffer: under load (ctest -j2 on 2 cores) this Python thread can fall
        # behind a replay at full speed, and the kernel drops what does not fit (drops are checked).
        sock.setsockopt(socket.SOL_SOCKET, getattr(socket, "SO_RCVBUFFORCE", 33), 64 << 20)
        sock.bind(("lo", 0))
        sock.settimeout(0.2)
        payloads, stop = [], threading.Event()

        def sniff():
            deadline = time.monotonic() + 90  # bounded even if the processes hang
            while not stop.is_set() and time.monotonic() < deadline:
                try:
                    frame = sock.recv(65535)
                except socket.timeout:
                    continue
                ip = frame[14:]
                if len(ip) < 28 or ip[0] >> 4 != 4 or ip[9] != 17:
                    continue
                ihl = (ip[0] & 0x0F) * 4
                sport, dport = struct.unpack("!HH", ip[ihl:ihl + 4])
                if base <= sport < base + 250 or base <= dport < base + 250:
                    payloads.append(ip[ihl + 8:])

        t = threading.Thread(target=sniff)
        t.start()
        try:
            common = ["--dds-domain", str(self.DOMAIN), "--dds-profile", UDP_PROFILE, "--dds-profile-name", "hil_udp_loopback"]
            echo = start(*common, *ks_echo, "echo", "pose_wrench", "-n", str(N), "--timeout", "60")
            time.sleep(0.3)
            replay = hil(*common, *ks_replay, "replay", RUN, "--speed", "0", "--wait-subscribers", "1", "--wait-timeout", "60")
            rc, out, err = finish(echo)
        finally:
            stop.set()
            t.join()
            # struct tpacket_stats {packets, drops}: a capture with drops proves nothing either way.
            received, dropped = struct.unpack("II", sock.getsockopt(263, 6, 8))  # SOL_PACKET, PACKET_STATISTICS
            sock.close()
        self.assertEqual(dropped, 0, "the capture lost %d of %d packets" % (dropped, received))
        self.assertEqual(replay.returncode, 0, replay.stderr)
        self.assertEqual(rc, 0, err)
        self.assertEqual(samples(out), list(range(N)))
        return payloads

    def test_samples_cross_loopback_encrypted(self):
        if os.geteuid() != 0:
            self.skipTest("capturing on lo needs root (AF_PACKET)")
        ks = Keystore(self)
        plain = b"".join(self.capture([], []))
        packets = self.capture(ks.secure("echo"), ks.secure("replay"))
        secret = b"".join(packets)
        # The authentication handshake carries certificates and permissions in the clear (as the
        # DDS Security spec has it: they are signed, not secret); everything after it is encrypted.
        after_handshake = b"".join(p for p in packets if b"DDS:Auth:PKI-DH" not in p)
        # Without security the samples' frame_id, the topic and the type are on the wire...
        for marker in (b"world", b"rt/hil/pose_wrench", b"PoseWrenchSample"):
            self.assertIn(marker, plain)
        # ...with it none of them, although as many samples crossed (ciphertext is not smaller).
        self.assertGreater(len(secret), len(plain) // 2)
        self.assertFalse(b"world" in secret, "the samples' frame_id 'world' is on the wire in the clear")
        self.assertFalse(b"PoseWrenchSample" in secret, "the type name is on the wire in the clear")
        self.assertFalse(b"rt/hil/pose_wrench" in after_handshake, "the topic name is on the wire outside the handshake")
        self.assertTrue(any(b"c.perm" in p for p in packets))  # the handshake was seen (the filter is not vacuous)


class Unauthorised(unittest.TestCase):
    """Beside an authorised pair (the control: it must get everything), an outsider gets and injects
    nothing. Each test on its own domain."""

    def test_no_certificate_receives_nothing(self):
        ks, domain = Keystore(self), "38"
        good = start("--dds-domain", domain, *ks.secure("echo"), "echo", "pose_wrench", "-n", str(N), "--timeout", "60")
        outsider = start("--dds-domain", domain, "echo", "pose_wrench", "-n", "1", "--timeout", LISTEN_S)
        time.sleep(0.3)
        replay = hil("--dds-domain", domain, *ks.secure("replay"), "replay", RUN, "--speed", "4", "--wait-subscribers", "1",
                     "--wait-timeout", "60")
        self.assertEqual(replay.returncode, 0, replay.stderr)
        rc, out, err = finish(good)
        self.assertEqual(samples(out), list(range(N)), err)
        # With -n 1 the outsider would have ended on its first sample.
        self.assertIsNone(outsider.poll(), "the outsider stopped listening before the replay ended")
        rc, out, err = stop(outsider)
        self.assertEqual(samples(out), [])
        self.assertEqual(rc, 0, err)  # ended by the test, not by a failure

    def test_no_certificate_injects_nothing(self):
        ks, domain = Keystore(self), "39"
        # Count everything until both replays ended: the authorised replay's N samples, and the
        # intruder's if it got through.
        victim = start("--dds-domain", domain, *ks.secure("echo"), "echo", "pose_wrench", "--timeout", LISTEN_S)
        time.sleep(0.3)
        intruder = start("--dds-domain", domain, "replay", RUN, "--speed", "3")
        replay = hil("--dds-domain", domain, *ks.secure("replay"), "replay", RUN, "--speed", "3", "--wait-subscribers", "1",
                     "--wait-timeout", "60")
        self.assertEqual(replay.returncode, 0, replay.stderr)
        self.assertEqual(finish(intruder)[0], 0)  # it did publish, unmatched
        self.assertIsNone(victim.poll(), "the subscriber stopped before both replays ended")
        rc, out, err = stop(victim)
        self.assertEqual(rc, 0, err)
        self.assertEqual(samples(out), list(range(N)))  # once each: nothing from the intruder

    def test_certificate_from_another_ca_is_not_let_in(self):
        # Keystores made the same way, with the same CA names, but other keys; spy and intruder from
        # two of them so that they cannot talk to each other either.
        ks, rogue1, rogue2, domain = Keystore(self), Keystore(self), Keystore(self), "41"
        good = start("--dds-domain", domain, *ks.secure("echo"), "echo", "pose_wrench", "-n", str(N), "--timeout", "60")
        spy = start("--dds-domain", domain, *rogue1.secure("echo"), "echo", "pose_wrench", "-n", "1", "--timeout", LISTEN_S)
        time.sleep(0.3)
        intruder = start("--dds-domain", domain, *rogue2.secure("replay"), "replay", RUN, "--speed", "3")
        replay = hil("--dds-domain", domain, *ks.secure("replay"), "replay", RUN, "--speed", "3", "--wait-subscribers", "1",
                     "--wait-timeout", "60")
        self.assertEqual(replay.returncode, 0, replay.stderr)
        self.assertEqual(finish(intruder)[0], 0)  # it did publish, unmatched
        rc, out, err = finish(good)
        self.assertEqual(samples(out), list(range(N)), err)  # once each: nothing from the rogue replay
        self.assertIsNone(spy.poll(), "the spy stopped listening before the replays ended")
        rc, out, err = stop(spy)
        self.assertEqual(samples(out), [])
        self.assertEqual(rc, 0, err)

    def test_permissions_for_other_topics(self):
        ks, domain = Keystore(self), "40"
        good = start("--dds-domain", domain, *ks.secure("echo"), "echo", "pose_wrench", "-n", str(N), "--timeout", "60")
        time.sleep(0.3)
        # `other` may neither subscribe to nor publish pose_wrench: Fast DDS refuses the reader and the writer.
        spy = hil("--dds-domain", domain, *ks.secure("other"), "echo", "pose_wrench", "-n", "1", "--timeout", "3")
        self.assertEqual(spy.returncode, 1, spy.stderr)
        self.assertEqual(samples(spy.stdout), [])
        self.assertIn("permissions do not allow subscribing", spy.stderr)
        inject = hil("--dds-domain", domain, *ks.secure("other"), "replay", RUN, "--speed", "0")
        self.assertEqual(inject.returncode, 1, inject.stderr)
        self.assertIn("permissions do not allow publishing", inject.stderr)
        self.assertNotIn("samples published", inject.stderr)
        replay = hil("--dds-domain", domain, *ks.secure("replay"), "replay", RUN, "--speed", "0", "--wait-subscribers", "1",
                     "--wait-timeout", "60")
        self.assertEqual(replay.returncode, 0, replay.stderr)
        rc, out, err = finish(good)
        self.assertEqual(samples(out), list(range(N)), err)  # the control, and nothing from `other`


class BadKeystore(unittest.TestCase):
    """Refused before joining the bus: exit 2 and one line naming the file and what is wrong."""

    def refused(self, *args):
        r = hil("--dds-domain", "36", *args, "echo", "pose_wrench", "--timeout", "1")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertEqual(r.stdout, "")
        return r.stderr

    def test_tampered_permissions(self):
        ks = Keystore(self)
        path = os.path.join(ks.dir, "participants", "echo", "permissions.p7s")
        with open(path, "rb") as f:
            data = bytearray(f.read())
        i = data.index(b"rt/hil/pose_wrench")
        data[i + 7] = ord("*")  # rt/hil/*ose_wrench: one byte, after signing
        with open(path, "wb") as f:
            f.write(data)
        err = self.refused(*ks.secure("echo"))
        self.assertIn("participants/echo/permissions.p7s", err)
        self.assertIn("signature does not verify against the permissions CA", err)
        r = hil("keystore", "check", ks.dir, "echo")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("participants/echo/permissions.p7s", r.stderr)
        self.assertIn("signature does not verify against the permissions CA", r.stderr)

    def test_tampered_governance(self):
        ks = Keystore(self)
        path = os.path.join(ks.dir, "governance.p7s")
        with open(path) as f:
            text = f.read()
        with open(path, "w") as f:
            tampered = text.replace("<data_protection_kind>ENCRYPT", "<data_protection_kind>NONE", 1)
            self.assertNotEqual(tampered, text)
            f.write(tampered)
        err = self.refused(*ks.secure("echo"))
        self.assertIn("governance.p7s: signature does not verify", err)

    def test_permissions_of_another_participant(self):
        ks = Keystore(self)
        shutil.copy(os.path.join(ks.dir, "participants", "replay", "permissions.p7s"),
                    os.path.join(ks.dir, "participants", "echo", "permissions.p7s"))
        err = self.refused(*ks.secure("echo"))
        self.assertIn("participants/echo/permissions.p7s", err)
        self.assertIn("not for this participant's certificate (CN=echo,O=hil)", err)

    def test_missing_files(self):
        ks = Keystore(self)
        os.remove(os.path.join(ks.dir, "participants", "echo", "key.pem"))
        err = self.refused(*ks.secure("echo"))
        self.assertIn("participants/echo/key.pem: private key of participant 'echo' not found", err)
        err = self.refused(*ks.secure("nobody"))
        self.assertIn("participants/nobody/cert.pem", err)
        self.assertIn("hil keystore add", err)
        err = self.refused("--secure", os.path.join(ks.dir, "nowhere"))
        self.assertIn("nowhere: keystore not found", err)

    def test_keystore_command_errors(self):
        ks = Keystore(self)
        r = hil("keystore", "create", ks.dir)
        self.assertEqual(r.returncode, 2)
        self.assertIn("already holds a keystore", r.stderr)
        r = hil("keystore", "add", ks.dir, "x", "--publish", "pose_wrench")
        self.assertEqual(r.returncode, 2)
        self.assertIn("'--publish': expected a DDS topic", r.stderr)
        r = hil("keystore", "add", ks.dir, "a b", "--publish", "/hil/x")
        self.assertEqual(r.returncode, 2)
        self.assertIn("'a b'", r.stderr)
        r = hil("keystore", "add", ks.dir, "x")
        self.assertEqual(r.returncode, 2)
        self.assertIn("no topic", r.stderr)
        r = hil("keystore", "add", ks.dir, "x", "--publish", "/hil/x", "--days", "0")
        self.assertEqual(r.returncode, 2)
        self.assertIn("--days", r.stderr)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v", *sys.argv[3:]])
