/* The course's book: the theme's search button names itself "Search" while it shows
   "Search Ctrl+K"; let its visible text be its name (WCAG 2.5.3, axe label-content-name-mismatch). */
document.addEventListener("DOMContentLoaded", () => {
  document.querySelectorAll(".search-button-field[aria-label]").forEach(
    (button) => button.removeAttribute("aria-label"));
});
