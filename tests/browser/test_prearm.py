"""The page of a ready team lists the checks before arming that fail, before ARM is pressed.

The real simulator in lockstep (:class:`gcs.testing.SimTeam`), vehicle 3's bank
limit raised over the team file's
(:func:`tests.support.flights.ready_with_vehicle_3_raised`); its page
(:class:`web.WebUi`) served in this process and viewed by headless Chromium.
"""

from __future__ import annotations

import pytest

from gcs.app import free_tcp_port
from tests.browser.test_live_demo import headless_chromium, wait_for
from tests.browser.test_view import open_viewer
from tests.support.flights import SQUARE_FILE, TOO_STEEP, ready_with_vehicle_3_raised
from web import WebUi


@pytest.fixture(scope="module")
def browser(tmp_path_factory):  # type: ignore[no-untyped-def]
    yield from headless_chromium(tmp_path_factory)


def test_the_ready_page_shows_a_failing_check(sim_team, browser) -> None:  # type: ignore[no-untyped-def]
    team = sim_team(SQUARE_FILE, seed=1)
    ready_with_vehicle_3_raised(team)
    ui = WebUi(team.app, port=free_tcp_port())
    ui.start()
    page = None
    try:
        page, _ = open_viewer(browser, ui)
        banner = page.locator("[data-gcs-banner=prearm]")
        checks = page.locator("[data-gcs=prearm-check]")
        # the banner and its lines may come in two updates (seen apart on a loaded machine)
        wait_for(lambda: banner.count() == 1 and checks.count() > 0, 20,
                 "the checks' banner and lines",
                 lambda: page.locator("[data-gcs=phase]").inner_text())
        lines = checks.all_inner_texts()
        print(f"the ready page says: {banner.inner_text()!r}")
        assert banner.inner_text().startswith("ARM WOULD BE REFUSED: 1 check before arming fails")
        assert len(lines) == 1 and lines[0].startswith(TOO_STEEP), lines
    finally:
        if page is not None:
            page.context.close()
        ui.close()
