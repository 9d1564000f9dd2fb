/* The course's book: small additions to sphinx-book-theme 1.4 on pydata-sphinx-theme 0.20. */

/* Search from disk (file://): Sphinx would fetch every result's page for a snippet, which a
   browser refuses there (one console error per result); titles only. Served: snippets. */
if (window.location.protocol === "file:" && typeof DOCUMENTATION_OPTIONS !== "undefined") {
  DOCUMENTATION_OPTIONS.SHOW_SEARCH_SUMMARY = false;
}

document.addEventListener("DOMContentLoaded", () => {
  /* The theme's search button names itself "Search" while it shows "Search Ctrl+K"; let its
     visible text be its name (WCAG 2.5.3, axe label-content-name-mismatch). */
  document.querySelectorAll(".search-button-field[aria-label]").forEach(
    (button) => button.removeAttribute("aria-label"));

  /* The menu and the page's contents buttons: pydata-sphinx-theme wires only the FIRST
     .primary-toggle / .secondary-toggle (in its header, hidden by sphinx-book-theme), so the
     visible buttons of the article's header do nothing (pydata-sphinx-theme#2451,
     sphinx-book-theme#988). A visible button's click goes to the wired one: on a wide screen it
     hides or shows the sidebar, on a narrow one it opens the theme's dialog. */
  ["primary-toggle", "secondary-toggle"].forEach((name) => {
    const [wired, ...visible] = document.querySelectorAll(`.${name}`);
    visible.forEach((button) => button.addEventListener("click", (event) => {
      event.preventDefault();
      event.stopPropagation();
      wired.click();
    }));
  });
});
