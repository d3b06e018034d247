"""Webhook alerts (``burstloc monitor --db ... --webhook URL``): a JSON POST to each URL for
every new incident and, with an escalation time, for an incident still unacknowledged after it;
delivered off the monitor's path, in order and once each per URL, through receivers that are
down for hours and monitors that restart.

* :mod:`~burstloc.incidents.alerts.config`: the URLs, checked, and the limits of delivery;
* :mod:`~burstloc.incidents.alerts.payload`: the JSON a receiver gets;
* :mod:`~burstloc.incidents.alerts.outbox`: the durable outbox, a table of the incident store
  written in the transaction that opens the incident;
* :mod:`~burstloc.incidents.alerts.sender`: the threads that deliver it, with retries and a
  dead-letter file;
* :mod:`~burstloc.incidents.alerts.pacing`: a replayed file's alerts held to the file's clock.

This package imports the incident store's modules and the standard library (HTTP by
:mod:`urllib`); SQLAlchemy only with :mod:`~burstloc.incidents.alerts.outbox`,
:mod:`~burstloc.incidents.alerts.sender` and :mod:`~burstloc.incidents.alerts.pacing`, which
are imported once a store is open.
"""

from __future__ import annotations

from burstloc.incidents.alerts.config import WebhookSettings, check_url

__all__ = ["WebhookSettings", "check_url"]
