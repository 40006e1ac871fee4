"""``footfall teach``: people label footholds on run logs in the browser (paper §II-B)."""

from __future__ import annotations

import json
import webbrowser

import click

from footfall.cli.output import json_option
from footfall.teach.server import address, bind, new_token, serve
from footfall.teach.service import TeachService


@click.command("teach")
@click.argument("store_path", metavar="STORE.sqlite")
@click.option("--labeler", default=None, metavar="NAME",
              help="Whose labels the page gives (the page asks if not given).")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to listen on; anything but loopback serves your network, so only "
                   "change it on purpose (the token still guards every request).")
@click.option("--port", type=click.IntRange(0, 65535), default=0, show_default=True,
              help="Port to listen on (0: a free one).")
@click.option("--open", "open_browser", is_flag=True, help="Open the page in a browser.")
@json_option
def teach(store_path: str, labeler: str | None, host: str, port: int, open_browser: bool,
          as_json: bool) -> None:
    """Serve a store's runs for labelling: open the printed address, pick a run, step through
    it, click the foothold the robot should have chosen. Labels are demonstrations with source
    'human' (footfall learn STORE --source human). Ctrl-C stops the server. With --json the
    address is printed as a JSON line when serving starts, and a second line when it stops."""
    service = TeachService(store_path, labeler=labeler)
    sock = bind(host, port)
    token = new_token()
    url = address(sock, token)
    bound = sock.getsockname()
    if as_json:
        click.echo(json.dumps({"serving": store_path, "url": url, "host": bound[0],
                               "port": bound[1], "labeler": service.labeler}))
    else:
        click.echo(f"footfall teach: serving {store_path} at\n    {url}\n(Ctrl-C stops it)")
    if open_browser:
        webbrowser.open(url)
    serve(service, sock, token)
    click.echo(json.dumps({"stopped": store_path}) if as_json else "footfall teach: stopped")
