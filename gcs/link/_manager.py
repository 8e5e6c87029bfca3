"""All of the GCS's links, opened from configuration and closed together.

:class:`LinkManager` builds one transport, :class:`~gcs.link.Link` and
autopilot profile per configured vehicle, shares one zenoh session among the
zenoh links, and feeds :class:`~gcs.link._discovery.Discovery` from zenoh
liveliness tokens and from the links' heartbeats. A vehicle heard for the
first time (and again after it vanished: a rebooted autopilot forgets) is
prepared by its profile on a thread of its own (the telemetry
rates a real autopilot is asked for, :meth:`AutopilotProfile.prepare`); what
it refuses is reported through ``on_note``.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import zenoh

from gcs.common import join_thread
from gcs.config import ZENOH, GcsLinkConfig, LinkConfig, check_links, link_key
from gcs.link._discovery import Discovery, PresenceEvent, PresenceSource
from gcs.link._errors import CommandResult, LinkError
from gcs.link._link import Link
from gcs.link._profile import AutopilotProfile
from gcs.link._profiles import make_profile
from gcs.transport import (
    FleetReceiver,
    MavutilTransport,
    Transport,
    ZenohTransport,
    open_session,
    watch_alive,
)
from gcs.wire import SigningKey
from gcs.wire.keys import Direction

__all__ = ["LinkManager"]

_log = logging.getLogger(__name__)


class LinkManager:
    """Opens every configured link at construction; use as a context manager or call close().

    One thread checks presence and sends every link's periodic HEARTBEAT and
    TIMESYNC (:meth:`Link.service`), however many links there are.
    """

    def __init__(self, links: Sequence[LinkConfig], *, settings: GcsLinkConfig | None = None,
                 base_dir: str | Path = ".", session: zenoh.Session | None = None,
                 clock: Callable[[], float] = time.monotonic,
                 on_presence: Callable[[PresenceEvent], None] | None = None,
                 on_note: Callable[[str, str], None] | None = None,
                 check_period_s: float = 0.1) -> None:
        self._settings = settings if settings is not None else GcsLinkConfig()
        check_links(links, gcs_system_id=self._settings.system_id, source="<links>")
        self._base_dir = Path(base_dir)
        self._clock = clock
        self._check_period_s = check_period_s
        self._on_note = on_note
        self._prepared: set[int] = set()  # vehicles whose profile ran prepare() (check loop)
        self.discovery = Discovery((c.sysid for c in links), clock=clock, on_event=on_presence)
        """Presence of the vehicles."""
        self._owns_session = False
        self._session = session
        self._links: dict[int, Link] = {}
        self._profiles: dict[int, AutopilotProfile] = {}
        self._watcher: zenoh.Subscriber | None = None
        self._receiver: FleetReceiver | None = None
        self._stop = threading.Event()
        self._checker: threading.Thread | None = None
        # One send lock for every link: a Fanout sends the fleet's setpoints under it at once.
        self._send_lock = threading.Lock()
        # Configuration errors (key files) before any port or session is opened.
        keys = {c.sysid: self._load_key(c) for c in links}
        try:
            if any(c.transport == ZENOH for c in links):
                if self._session is None:
                    self._session = open_session(self._settings.zenoh)
                    self._owns_session = True
                self._receiver = FleetReceiver(self._session, fleet=self._settings.fleet,
                                               direction=Direction.FROM_VEHICLE)
                self._watcher = watch_alive(
                    self._session, fleet=self._settings.fleet,
                    on_change=lambda sysid, up: self.discovery.report(
                        sysid, up, PresenceSource.LIVELINESS))
            # One thread sends every link's HEARTBEAT and TIMESYNC (the check loop), their
            # phases spread over the period so a hundred links do not send in one burst.
            periods = [p for p in (self._settings.heartbeat_period_s,
                                   self._settings.timesync_period_s) if p > 0]
            spread = min(periods, default=0.0) / max(1, len(links))
            for k, config in enumerate(links):
                link = self._open(config, keys[config.sysid], service_offset_s=k * spread)
                self._links[config.sysid] = link
                self._profiles[config.sysid] = make_profile(config.profile, link)
        except BaseException:
            self.close()
            raise
        self._checker = threading.Thread(target=self._check_loop, daemon=True,
                                         name="link-presence")
        self._checker.start()

    @property
    def links(self) -> Mapping[int, Link]:
        """Link per vehicle system id (read-only view)."""
        return MappingProxyType(self._links)

    @property
    def profiles(self) -> Mapping[int, AutopilotProfile]:
        """Autopilot profile per vehicle system id (read-only view)."""
        return MappingProxyType(self._profiles)

    @property
    def session(self) -> zenoh.Session | None:
        """The zenoh session, if any link uses zenoh."""
        return self._session

    def wait_received(self, sent: Mapping[int, int], timeout_s: float) -> bool:
        """Block until the zenoh links hold every payload counted in ``sent`` (see
        :meth:`FleetReceiver.wait_received`); True at once without zenoh links."""
        if self._receiver is None:
            return True
        return self._receiver.wait_received(sent, timeout_s)

    def missing(self) -> tuple[int, ...]:
        """Configured vehicles not present (see :meth:`Discovery.missing`)."""
        return self.discovery.missing()

    def close(self) -> None:
        """Close every link, the presence watch and an owned zenoh session; idempotent."""
        self._stop.set()
        join_thread(self._checker, 2.0, what="the presence check")
        for link in self._links.values():
            link.close()
        if self._receiver is not None:
            self._receiver.close()
            self._receiver = None
        if self._watcher is not None:
            with contextlib.suppress(zenoh.ZError):  # session already closed
                self._watcher.undeclare()
            self._watcher = None
        if self._owns_session and self._session is not None:
            self._session.close()
            self._session = None

    def __enter__(self) -> LinkManager:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def _load_key(self, config: LinkConfig) -> SigningKey | None:
        return link_key(config, settings=self._settings, base_dir=self._base_dir)

    def _open(self, config: LinkConfig, key: SigningKey | None, *,
              service_offset_s: float) -> Link:
        transport: Transport
        if config.transport == ZENOH:
            assert self._session is not None
            transport = ZenohTransport.for_gcs(self._session, fleet=self._settings.fleet,
                                               sysid=config.sysid, receiver=self._receiver)
        else:
            try:
                transport = MavutilTransport(config.transport, baud=config.baud)
            except (RuntimeError, ValueError) as exc:
                raise LinkError(config.sysid, str(exc)) from None
        try:
            link = Link(config.sysid, transport, gcs_system_id=self._settings.system_id,
                        gcs_component_id=self._settings.component_id,
                        target_component=config.component_id, signing_key=key,
                        signing_link_id=config.signing_link_id, clock=self._clock,
                        command_timeout_s=config.command_timeout_s,
                        command_retries=config.command_retries,
                        heartbeat_timeout_s=config.heartbeat_timeout_s,
                        gcs_heartbeat_period_s=self._settings.heartbeat_period_s,
                        timesync_period_s=self._settings.timesync_period_s,
                        service_offset_s=service_offset_s, send_lock=self._send_lock)
            return link.start(background=False)
        except BaseException:
            transport.close()
            raise

    def _check_loop(self) -> None:
        while not self._stop.wait(self._check_period_s):
            now = time.monotonic()
            for sysid, link in list(self._links.items()):
                try:  # one link's fault must not stop every link's heartbeat
                    link.service(now)
                    alive = link.health.alive
                    self.discovery.report(sysid, alive, PresenceSource.HEARTBEAT)
                    if not alive:  # a rebooted autopilot forgets the rates it was asked for
                        self._prepared.discard(sysid)
                    elif sysid not in self._prepared:
                        self._prepared.add(sysid)
                        threading.Thread(target=self._prepare, args=(sysid,), daemon=True,
                                         name=f"link-prepare-{sysid}").start()
                except Exception:
                    _log.exception("link %d: heartbeat or presence check failed", sysid)

    def _prepare(self, sysid: int) -> None:
        """Run the vehicle's :meth:`AutopilotProfile.prepare` (it blocks on acks); report what
        it refused, or why it failed, as one note."""
        try:
            results = self._profiles[sysid].prepare()
        except LinkError as exc:
            if not self._links[sysid].closed:  # closing mid-request is no news
                self._note("warning", f"{exc}: telemetry rates not set")
            return
        refused = [f"{name} ({result.name})" for name, result in results.items()
                   if result is not CommandResult.ACCEPTED]
        if refused:
            self._note("warning", f"vehicle {sysid}: telemetry rate not set for "
                                  f"{', '.join(refused)}: streamed at the autopilot's own rate")
        elif results:
            self._note("info", f"vehicle {sysid}: telemetry rates set for {', '.join(results)}")

    def _note(self, level: str, text: str) -> None:
        _log.log(logging.WARNING if level == "warning" else logging.INFO, "%s", text)
        if self._on_note is not None:
            self._on_note(level, text)
