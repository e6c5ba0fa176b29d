"""A pytest plugin: the suite's ``--dist loadfile`` made safe against a worker that dies.

A worker process can die in a native library rather than in a test's assertion (XLA's
compiler aborting with SIGABRT, say). pytest-xdist 3.8's file scheduler then puts the
dead worker's whole workload back on the queue, files already finished included, and a
worker handed an empty file or a lone test waits forever: the run hangs (pytest-xdist
issues 784, 1327 and 1378).

This scheduler requeues only the dead worker's unfinished files, first in the queue;
runs the test it died in once more, in a fresh worker (reported ``R``, with the crash in
the summary); fails that test if its worker dies again; and gives a worker a second
test whenever it holds fewer than two, which the worker needs before it runs one.
"""

import pytest
from xdist.scheduler import LoadFileScheduling


class CrashTolerantLoadFile(LoadFileScheduling):
    """``--dist loadfile`` whose recovery from a dead worker neither hangs nor drops
    tests; a test a worker died in runs once more."""

    def __init__(self, config, log=None):
        super().__init__(config, log)
        self.crashed: set[str] = set()  # tests a worker died in
        self.rerun: set[str] = set()  # of those, the ones that run again

    def remove_node(self, node):
        workload = self.assigned_work.pop(node)
        unfinished = {scope: unit for scope, unit in workload.items()
                      if not all(unit.values())}
        if not unfinished:
            return None
        crashed = next(nodeid for unit in unfinished.values()
                       for nodeid, done in unit.items() if not done)
        if crashed in self.crashed:
            self.rerun.discard(crashed)
            unfinished[self._split_scope(crashed)][crashed] = True
            unfinished = {scope: unit for scope, unit in unfinished.items()
                          if not all(unit.values())}
        else:
            self.rerun.add(crashed)
        self.crashed.add(crashed)
        for scope, unit in reversed(list(unfinished.items())):
            self.workqueue[scope] = unit
            self.workqueue.move_to_end(scope, last=False)
        for other in self.assigned_work:
            self._reschedule(other)
        return crashed

    def _reschedule(self, node):
        super()._reschedule(node)
        # a worker runs a test only once it holds the next one (or is told to stop)
        while not node.shutting_down and self._pending_of(self.assigned_work[node]) < 2:
            if not self.workqueue:
                node.shutdown()
            else:
                self._assign_work_unit(node)


@pytest.hookimpl(tryfirst=True)
def pytest_xdist_make_scheduler(config, log):
    if config.getvalue("dist") == "loadfile":
        return CrashTolerantLoadFile(config, log)
    return None


def pytest_handlecrashitem(crashitem, report, sched):
    if isinstance(sched, CrashTolerantLoadFile) and crashitem in sched.rerun:
        report.outcome = "rerun"


def pytest_report_teststatus(report, config):
    if report.outcome == "rerun":
        return "rerun", "R", ("RERUN", {"yellow": True})
    return None


def pytest_terminal_summary(terminalreporter):
    reruns = terminalreporter.stats.get("rerun", [])
    if reruns:
        terminalreporter.section("worker deaths: tests run again in a fresh worker")
        for report in reruns:
            terminalreporter.line(str(report.longrepr))
