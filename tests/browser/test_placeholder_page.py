"""The placeholder dashboard opens in headless Chromium and shows its content."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from app.main import TITLE

pytestmark = pytest.mark.browser


def test_placeholder_page_shows_title(page, dashboard_url):
    page.goto(dashboard_url)
    expect(page).to_have_title(TITLE)
    # Header text is part of the page template ...
    expect(page.get_by_text(TITLE).first).to_be_visible(timeout=30_000)
    # ... the markdown appears only once BokehJS has rendered the session's models.
    expect(page.get_by_text("amra simulate").first).to_be_visible(timeout=30_000)
