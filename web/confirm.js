/*
 * confirm.js - a confirmation in a modal <dialog> (dialog#confirm-dialog): a title, a sentence
 * and two buttons, button#confirm-yes (the action, named) and button#confirm-no ("Keep it"),
 * the latter focused first so that Enter never destroys anything by accident. Escape, the "Keep
 * it" button and closing the dialog all answer false. The dialog is labelled and described by
 * its title and sentence (aria-labelledby, aria-describedby) and removed when answered.
 */
import {el} from "./dom.js";

/* Resolves true when the user confirms, false otherwise. */
export function confirmDialog({title, text, action, danger = true}) {
  return new Promise((resolve) => {
    const yes = el("button", {type: "button", id: "confirm-yes", class: danger ? "danger" : "primary", text: action});
    const no = el("button", {type: "button", id: "confirm-no", text: "Keep it"});
    const dialog = el("dialog", {id: "confirm-dialog", "aria-labelledby": "confirm-title",
      "aria-describedby": "confirm-text"},
    el("h2", {id: "confirm-title", text: title}),
    el("p", {id: "confirm-text", text}),
    el("div", {class: "buttons"}, no, yes));
    let answer = false;
    yes.addEventListener("click", () => { answer = true; dialog.close(); });
    no.addEventListener("click", () => dialog.close());
    dialog.addEventListener("close", () => { dialog.remove(); resolve(answer); });
    document.body.append(dialog);
    dialog.showModal();
    no.focus();
  });
}
