"""A run's CCSDS set written while the run goes (the ``ground_bridge`` node's output), without ROS: the messages
received so far, and a writer thread that writes the set from a snapshot of them on request. Building and writing
the set of a whole run takes tenths of a second (seed 5: 0.7 s) to seconds for a long run, during which the caller
(a node's executor) must keep taking messages.

The final set is the complete set of every message received. A complete set written earlier from a snapshot that
already held them all (one requested when the scenario reported its end, :meth:`LiveSet.request`) is that final
set: :meth:`LiveSet.finish` then has nothing left to write, and a process stopping after its scenario does not
wait for the set a second time."""

import queue
import threading

from .options import RunMessages


class LiveSet:
    """The set of ``opts`` (:class:`~.options.Options`) in ``out`` (a directory) as ``fmt`` files, from the messages
    :meth:`add` received; ``now()`` the sim time [s] of a write (``written``: file stem -> sim time of its last write);
    ``on_error(exc)`` when a write fails (the thread goes on)."""

    def __init__(self, out, fmt, opts, now, on_error):
        self.out, self.fmt, self.opts = out, fmt, opts
        self.now, self.on_error = now, on_error
        self.run = RunMessages()
        self.lock = threading.Lock()
        self.requests = queue.Queue()
        self.written = {}  # file stem -> sim time of the last write
        self.received = 0  # messages added so far
        self.complete = -1  # of them, how many the last complete set written without error was made from
        self.finishing = False  # the final set is queued (:meth:`finish`)
        self.writer = threading.Thread(target=self._writer, name="ccsds_writer", daemon=True)
        self.writer.start()

    def add(self, topic, msg):
        with self.lock:
            self.run.add(topic, msg)
            self.received += 1

    def request(self, periodic):
        """Queue a write: the OPMs, and with ``periodic`` the OEM, TDM and CDM too."""
        self.requests.put(periodic)

    def finish(self):
        """Start the final, complete set (no message may be added any more): the writer thread finishes its queue,
        then writes everything once more unless the last complete set written already held every message, while the
        caller goes on with its own shutdown (:meth:`close` waits)."""
        if not self.finishing:
            self.finishing = True
            self.requests.put(None)

    def close(self):
        """The final, complete set (:meth:`finish`, if not started yet), written when this returns."""
        self.finish()
        self.writer.join()

    def _writer(self):
        from . import dataset  # noqa: F401  (load the NDM library here, while the executor already spins)

        while True:
            batch = [self.requests.get()]
            while not self.requests.empty():  # coalesce what queued up meanwhile
                batch.append(self.requests.get())
            if None in batch:  # shutdown: the final, complete set, unless it is on disk already
                if self.complete != self.received:
                    self.write(True)
                return
            self.write(any(batch))

    def write(self, periodic):
        """Write the OPMs (always: small) and, if ``periodic``, the OEM, TDM and CDM, from a snapshot of the
        messages received so far."""
        with self.lock:
            snapshot = RunMessages({t: list(ms) for t, ms in self.run.by_topic.items()})
            count = self.received
        try:
            from .dataset import messages_of  # the NDM library loads in this thread, not at start-up
            from .messages import write_message

            msgs = messages_of(snapshot, self.opts, periodic)
            for stem, message in msgs.items():
                write_message(self.out / f"{stem}.{self.fmt}", message, self.fmt)
                self.written[stem] = self.now()
        except Exception as exc:  # noqa: BLE001  (the writer thread must survive any bad input)
            self.on_error(exc)
        else:
            if periodic:
                self.complete = count
