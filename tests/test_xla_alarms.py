"""XLA's slow-compile alarm is kept off file descriptor 2; everything else passes."""

import os

from jaxrail._xla_alarms import hidden_xla_alarms

# The alarm as XLA logs it (xla/service/slow_operation_alarm.cc, at error level).
ALARM = (b"E1125 08:00:00.123456   4242 slow_operation_alarm.cc:73] \n"
         b"********************************\n"
         b"[Compiling module jit_solve] Very slow compile? If you want to file a bug, run "
         b"with envvar XLA_FLAGS=--xla_dump_to=/tmp/foo and attach the results.\n"
         b"********************************\n")


def test_alarm_is_dropped_and_the_rest_passes_in_order(capfd):
    with hidden_xla_alarms():
        os.write(2, b"\r0.04/2.00 s simulated |  | [00:00<00:02]")
        os.write(2, b"W1125 08:00:00.1 42 other.cc:1] a real warning\n")
        os.write(2, ALARM[:40])  # the alarm may arrive in pieces
        os.write(2, ALARM[40:])
        os.write(2, b"Traceback (most recent call last):\n  ...\nValueError: bad\n")
    err = capfd.readouterr().err
    assert "slow compile" not in err and "****" not in err and "slow_operation" not in err
    assert err == ("\r0.04/2.00 s simulated |  | [00:00<00:02]"
                   "W1125 08:00:00.1 42 other.cc:1] a real warning\n"
                   "Traceback (most recent call last):\n  ...\nValueError: bad\n")


def test_descriptor_2_is_restored(capfd):
    before = os.fstat(2).st_ino
    with hidden_xla_alarms():
        pass
    assert os.fstat(2).st_ino == before
    os.write(2, b"after\n")
    assert capfd.readouterr().err == "after\n"
